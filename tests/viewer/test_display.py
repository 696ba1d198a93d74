"""The viewer's display images (viewer/display.py) without a window: after every frame, however
it updated, the shown image is the film's full tone map."""
import numpy as np

from renderer.film.accumulation import Film
from renderer.film.pixel_slices import ROUND_SLICES, slice_mask
from renderer.output.tonemap import tonemap_packed, unpack_rgba8
from viewer.display import UPDATE_FULL, UPDATE_NONE, UPDATE_SLICES, DisplayImages, DisplaySettings

SIZE = (70, 40)  # cells of 16 cut at the right and top edges


class SlicedFilm:
    """A film that 'renders' pixel slices as the renderer does: each pixel of a slice gets one more
    sample (random radiance, running mean), and slices_done counts on through rounds."""

    def __init__(self, size, seed=1):
        self.film = Film(*size)
        self.rng = np.random.default_rng(seed)
        self.reset(size)

    def reset(self, size):
        self.film.reset(*size)
        self.mean = np.zeros((*self.film_shape(), 3), np.float32)
        self.count = np.zeros(self.film_shape(), np.int32)
        self.slices_done = 0

    def film_shape(self):
        return self.film.max_width, self.film.max_height

    def render(self, slices):
        width, height = self.film.width, self.film.height
        for s in range(self.slices_done, self.slices_done + slices):
            mask = np.zeros(self.film_shape(), bool)
            mask[:width, :height] = slice_mask(s % ROUND_SLICES, 1, width, height).T
            value = self.rng.lognormal(-1.0, 1.5, size=(int(mask.sum()), 3)).astype(np.float32)
            n = self.count[mask] + 1
            self.mean[mask] += (value - self.mean[mask]) / n[:, None]
            self.count[mask] = n
        self.slices_done += slices
        self.film.mean.from_numpy(self.mean)
        self.film.count.from_numpy(self.count)


def full_tone_map(film, shape, settings, slices_done):
    out = np.zeros(shape, np.uint32)
    tonemap_packed(film, out, settings.exposure, settings.tonemapper, filled=slices_done < ROUND_SLICES)
    return unpack_rgba8(out)


def test_still_frames_update_only_their_slices_and_show_the_full_tone_map():
    sliced = SlicedFilm(SIZE)
    display = DisplayImages(SIZE)
    settings = DisplaySettings(0.0, "aces")
    kinds = []
    # Frames of a few slices: through the first round's coarse grids (1, 4, 16, 64 slices),
    # across the end of a round (250 + 9), a frame of a whole round and more, a frame that
    # rendered nothing.
    for slices in (1, 2, 1, 12, 48, 7, 60, 119, 9, 4, 300, 0, 5):
        before = sliced.slices_done
        sliced.render(slices)
        kind = display.update(sliced.film, "accumulation 1", sliced.slices_done, settings)
        kinds.append(kind)
        assert display.shown is display.window_image
        np.testing.assert_array_equal(unpack_rgba8(display.shown),
                                      full_tone_map(sliced.film, SIZE, settings, sliced.slices_done))
        if slices == 0:
            assert kind == UPDATE_NONE
        elif before > 0 and slices < ROUND_SLICES:
            assert kind == UPDATE_SLICES  # only the pixels of the frame's slices (and their fill)
        else:
            assert kind == UPDATE_FULL  # a new accumulation, or a round's worth of slices
    assert kinds.count(UPDATE_SLICES) == 10


def test_display_settings_a_reset_or_a_smaller_film_update_everything():
    sliced = SlicedFilm(SIZE, seed=2)
    display = DisplayImages(SIZE)
    settings = DisplaySettings(0.0, "aces")
    sliced.render(100)
    assert display.update(sliced.film, "a", sliced.slices_done, settings) == UPDATE_FULL
    brighter = DisplaySettings(1.5, "aces")
    assert display.update(sliced.film, "a", sliced.slices_done, brighter) == UPDATE_FULL  # exposure alone
    np.testing.assert_array_equal(unpack_rgba8(display.shown), full_tone_map(sliced.film, SIZE, brighter, 100))
    assert display.update(sliced.film, "a", sliced.slices_done, brighter) == UPDATE_NONE
    # Moving: a reduced film's image goes to the canvas at its own size (GGUI stretches it).
    sliced.reset((17, 10))
    sliced.render(ROUND_SLICES)
    assert display.update(sliced.film, "b", sliced.slices_done, brighter) == UPDATE_FULL
    assert display.shown.shape == (17, 10) and display.shown.flags.c_contiguous
    np.testing.assert_array_equal(unpack_rgba8(display.shown), full_tone_map(sliced.film, (17, 10), brighter, 256))
    # A screenshot then tone-maps the window-sized image (bilinear), which the canvas does not show.
    image = display.window_sized_image(sliced.film, "b", sliced.slices_done, brighter)
    np.testing.assert_array_equal(image, full_tone_map(sliced.film, SIZE, brighter, ROUND_SLICES))
    assert display.shown.shape == (17, 10)
    # Back at full size after a reset: a full update, though the slice count is the same.
    sliced.reset(SIZE)
    sliced.render(ROUND_SLICES)
    assert display.update(sliced.film, "c", sliced.slices_done, brighter) == UPDATE_FULL
    assert display.shown is display.window_image


def test_iteration_steps_show_the_last_moving_frame_then_each_completed_iteration():
    """sppm in the viewer (pixel_sliced False): its slices are steps of whole-image iterations.
    Until the first iteration completes the canvas keeps the last moving frame; afterwards a
    frame updates everything when an iteration completed, and nothing otherwise."""
    film = SlicedFilm(SIZE, seed=3)
    display = DisplayImages(SIZE)
    settings = DisplaySettings(0.0, "aces")
    film.reset((17, 10))
    film.render(ROUND_SLICES)  # a moving frame: one whole iteration at the reduced size
    assert display.update(film.film, "moving", film.slices_done, settings, pixel_sliced=False) == UPDATE_FULL
    moving = display.shown.copy()
    film.reset(SIZE)  # still: full size, steps of the first iteration
    for steps in (40, 100):
        film.slices_done += steps  # (steps change no pixel of the film)
        assert display.update(film.film, "still", film.slices_done, settings, pixel_sliced=False) == UPDATE_NONE
        assert display.shown.shape == (17, 10)
        np.testing.assert_array_equal(display.shown, moving)
    film.slices_done = 0
    film.render(ROUND_SLICES)  # the iteration completes: the film changed everywhere
    assert display.update(film.film, "still", film.slices_done, settings, pixel_sliced=False) == UPDATE_FULL
    assert display.shown is display.window_image
    np.testing.assert_array_equal(unpack_rgba8(display.shown),
                                  full_tone_map(film.film, SIZE, settings, ROUND_SLICES))
    film.slices_done += 70  # steps of the next iteration
    assert display.update(film.film, "still", film.slices_done, settings, pixel_sliced=False) == UPDATE_NONE
    assert display.shown is display.window_image

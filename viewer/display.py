"""The images the canvas shows: the film tone-mapped into packed RGBA8, updated at the least cost.

GGUI's `Canvas.set_image` converts every image it is given into a staging array of packed RGBA8
with a kernel of its own (taichi/ui/staging_buffer.py, to_rgba8, even for u32 input): a second
pass over the window's pixels each frame (~13 ms at 960x540 on a 2-core CPU), on top of the tone
mapping. Here the tone mapping writes that layout itself (renderer/tonemap.tonemap_packed) and the
array goes to GGUI's canvas as it is (`show_on_canvas`).

A still frame changes only the pixels of the pixel slices it rendered (within a first round, also
the pixels shown filled from them: tonemap.fill_block_side), so only those are tone-mapped again;
a frame that rendered nothing and changed no display setting tone-maps nothing.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Hashable, Optional

import numpy as np
from taichi.ui.utils import get_field_info

from renderer.film.pixel_slices import INTERLEAVED, ROUND_SLICES
from renderer.output.tonemap import tonemap_array, tonemap_packed, unpack_rgba8

# What update() did, for the frame loop's accounting and for tests.
UPDATE_NONE = "none"
UPDATE_SLICES = "slices"
UPDATE_FULL = "full"


def show_on_canvas(canvas, packed: np.ndarray) -> None:
    """Put a packed RGBA8 image (uint32 (width, height), [x, y] y-up) on a GGUI canvas as it is.

    The Python Canvas.set_image would run its conversion kernel first (see the module docstring);
    the C++ canvas under it takes exactly this layout and copies it to its texture."""
    canvas.canvas.set_image(get_field_info(packed))


@dataclass(frozen=True)
class DisplaySettings:
    """Everything besides the film that decides the displayed pixels."""

    exposure: float
    tonemapper: str


class DisplayImages:
    """The packed display image on the canvas, at the film's active size.

    Still, that is the window's size. While moving the film is smaller: its image goes to the canvas
    at that size and GGUI stretches it over the window (bilinearly, texel centres on pixel centres),
    so tone mapping costs what the reduced render does, one lookup a pixel. Arrays rather than
    fields: the tone-mapping kernel compiles once per film for every size.

    `shown` holds the film `accumulation` (an identity that changes with every reset of the film)
    with `slices_shown` of its pixel slices, under `settings`; update() brings it to the film's
    current state with the least work.
    """

    def __init__(self, window_size: tuple[int, int]):
        self.window_image = np.zeros(window_size, np.uint32)
        self._reduced = np.zeros(window_size[0] * window_size[1], np.uint32)  # moving images are views of it
        self.shown = self.window_image
        self._state: Optional[tuple] = None  # (size, accumulation, settings) of `shown`
        self.slices_shown = 0

    def _image_for(self, size: tuple[int, int]) -> np.ndarray:
        if size == self.window_image.shape:
            return self.window_image
        return self._reduced[:size[0] * size[1]].reshape(size)  # contiguous, as the canvas needs

    def update(self, film, accumulation: Hashable, slices_done: int, settings: DisplaySettings,
               pixel_sliced: bool = True, round_order: Optional[Callable[[int], int]] = None) -> str:
        """Make `shown` the film's image (active region, `slices_done` pixel slices since its last
        reset); returns UPDATE_NONE, UPDATE_SLICES (only the pixels the slices rendered since the
        last update changed) or UPDATE_FULL.

        `pixel_sliced` False: the slices are steps of whole-image iterations (sppm), and the film
        changes everywhere when one completes; until the first has, the canvas keeps what it
        shows (the last moving frame) rather than an empty film. `round_order(slices_done)`: how
        the renderer cut the round holding that slice (Renderer.round_order; None: interleaved)."""
        size = (film.width, film.height)
        state = (size, accumulation, settings)
        if not pixel_sliced:
            return self._update_iterations(film, state, slices_done, settings)
        new_slices = slices_done - self.slices_shown if state == self._state else None
        self.shown = self._image_for(size)
        if new_slices == 0:
            return UPDATE_NONE
        if new_slices is not None and 0 < new_slices < ROUND_SLICES:
            first = self.slices_shown % ROUND_SLICES
            head = min(new_slices, ROUND_SLICES - first)
            first_round = self.slices_shown < ROUND_SLICES
            order_of = round_order or (lambda _done: INTERLEAVED)
            tonemap_packed(film, self.shown, settings.exposure, settings.tonemapper, filled=first_round,
                           slices=(first, head), first_round=first_round, order=order_of(self.slices_shown))
            if new_slices > head:  # the frame's slices ran on into the next round
                tonemap_packed(film, self.shown, settings.exposure, settings.tonemapper, filled=False,
                               slices=(0, new_slices - head), order=order_of(self.slices_shown + head))
            kind = UPDATE_SLICES
        else:
            tonemap_packed(film, self.shown, settings.exposure, settings.tonemapper,
                           filled=slices_done < ROUND_SLICES)
            kind = UPDATE_FULL
        self._state = state
        self.slices_shown = slices_done
        return kind

    def _update_iterations(self, film, state: tuple, slices_done: int, settings: DisplaySettings) -> str:
        if slices_done < ROUND_SLICES:
            return UPDATE_NONE
        self.shown = self._image_for(state[0])
        if state == self._state and slices_done // ROUND_SLICES == self.slices_shown // ROUND_SLICES:
            return UPDATE_NONE
        tonemap_packed(film, self.shown, settings.exposure, settings.tonemapper, filled=False)
        self._state = state
        self.slices_shown = slices_done
        return UPDATE_FULL

    def window_sized_image(self, film, accumulation: Hashable, slices_done: int, settings: DisplaySettings,
                           pixel_sliced: bool = True, round_order: Optional[Callable[[int], int]] = None
                           ) -> np.ndarray:
        """uint8 (height, width, 3), row 0 at the top: the film as the canvas shows it at the window
        size (a screenshot). While moving the canvas stretches a smaller image: then the film is
        tone-mapped into the window-sized image (bilinear), which is not on the canvas then."""
        if (film.width, film.height) == self.window_image.shape and (pixel_sliced or slices_done >= ROUND_SLICES):
            self.update(film, accumulation, slices_done, settings, pixel_sliced, round_order)
        else:
            tonemap_packed(film, self.window_image, settings.exposure, settings.tonemapper,
                           filled=pixel_sliced and slices_done < ROUND_SLICES)
            if self.shown is self.window_image:
                self._state = None  # not what it held any more: the next update fills it anew
        return unpack_rgba8(self.window_image)


def pack_rgba8_array(display: np.ndarray) -> np.ndarray:
    """uint8 (height, width, 3), row 0 at the top -> packed RGBA8 uint32 (width, height) [x, y] y-up,
    the layout of DisplayImages (the inverse of tonemap.unpack_rgba8)."""
    height, width = display.shape[:2]
    rgba = np.empty((width, height, 4), np.uint8)
    rgba[:, :, :3] = np.transpose(display[::-1], (1, 0, 2))
    rgba[:, :, 3] = 255
    return rgba.view(np.uint32).reshape(width, height)


class DenoisedDisplay:
    """The packed display image of a denoised result (viewer/denoise_worker.py), tone-mapped in numpy
    once per result and display setting (a new result comes at most every doubling of the spp)."""

    def __init__(self):
        self.packed: Optional[np.ndarray] = None
        self.display: Optional[np.ndarray] = None  # uint8 (height, width, 3), row 0 at the top
        self._key = None

    def update(self, result, settings: DisplaySettings) -> np.ndarray:
        key = (id(result), settings)
        if key != self._key:
            self.display = tonemap_array(result.image, settings.exposure, settings.tonemapper)
            self.packed = pack_rgba8_array(self.display)
            self._key = key
        return self.packed


__all__ = ["DenoisedDisplay", "pack_rgba8_array", "DisplayImages", "DisplaySettings", "UPDATE_FULL", "UPDATE_NONE", "UPDATE_SLICES", "show_on_canvas"]


HIGHLIGHT_COLOUR = (255, 170, 0)  # the picked object's tint, half over its pixels


def tinted(packed: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """A copy of a packed RGBA8 image (uint32 (width, height), y up) with the pixels of `mask` (bool,
    the same shape) halfway to HIGHLIGHT_COLOUR: the picked object, shown for a moment."""
    out = np.array(packed, dtype=np.uint32, copy=True)
    channels = out.view(np.uint8).reshape(*out.shape, 4)
    colour = np.array(HIGHLIGHT_COLOUR, np.uint16)
    channels[mask, :3] = ((channels[mask, :3].astype(np.uint16) + colour) // 2).astype(np.uint8)
    return out

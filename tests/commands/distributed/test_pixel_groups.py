"""Pixel groups of distributed renders: every pixel in exactly one slice, state in and out exactly."""
import numpy as np
import pytest

from renderer.film.adaptive import STOPPED
from renderer.commands.distributed.pixel_groups import DONE, PixelSlices, empty_state, group_count
from renderer.film.accumulation import Film
from renderer.film.pixel_slices import ROUND_SLICES, slice_mask


@pytest.mark.parametrize("size", [(64, 48), (37, 21), (8, 5)])
def test_slices_partition_the_image(size):
    width, height = size
    slices = PixelSlices(width, height)
    hits = np.zeros((height, width), int)
    for rank in range(ROUND_SLICES):
        xs, ys = slices.coords(rank, 1)
        hits[ys, xs] += 1
        expected = slice_mask(rank, 1, width, height)
        assert (hits[ys, xs] >= 1).all() and expected[ys, xs].all() and len(xs) == expected.sum()
    assert (hits == 1).all()


def random_state(width, height, seed=1):
    rng = np.random.default_rng(seed)
    state = empty_state(width, height, adaptive=True, aovs=True)
    for name in ("mean", "m2", "albedo", "normal"):
        getattr(state, name)[...] = rng.random(getattr(state, name).shape, np.float32)
    state.count[...] = rng.integers(0, 9, state.count.shape)
    state.rejected[...] = rng.integers(0, 2, state.count.shape)
    state.adaptive[...] = rng.integers(0, 3, state.count.shape)
    return state


def test_gather_scatter_round_trip():
    width, height = 40, 30
    source, target = random_state(width, height), empty_state(width, height, adaptive=True, aovs=True)
    slices = PixelSlices(width, height)
    for first in range(0, ROUND_SLICES, 32):
        slices.scatter(target, first, 32, slices.gather(source, first, 32))
    for name in ("mean", "m2", "count", "rejected", "adaptive", "albedo", "normal"):
        assert np.array_equal(getattr(source, name), getattr(target, name)), name


def test_film_pixels_move_exactly():
    """A worker's film takes and gives back a group's exact state, leaving other pixels alone."""
    width, height = 40, 30
    state, slices = random_state(width, height), PixelSlices(width, height)
    film = Film(width, height)
    film.reset(width, height)
    xs, ys = slices.coords(64, 64)
    arrays = slices.gather(state, 64, 64)
    film.write_pixels(xs, ys, arrays)
    back = film.read_pixels(xs, ys)
    for name in back:
        assert np.array_equal(back[name], arrays[name]), name
    other = ~slice_mask(64, 64, width, height)[::-1]
    assert (film.sample_counts()[other] == 0).all()


def test_progress_counts_sampling_pixels_only():
    width, height = 32, 32
    state = empty_state(width, height, adaptive=True, aovs=False)
    slices = PixelSlices(width, height)
    state.count[...] = 6
    xs, ys = slices.coords(10, 1)
    state.count[height - 1 - ys, xs] = 7  # slice 10 one sample ahead
    state.rejected[height - 1 - ys[:1], xs[:1]] = 1
    state.count[height - 1 - ys[:1], xs[:1]] = 6  # a rejected sample counts as taken
    xs, ys = slices.coords(20, 1)
    state.adaptive[height - 1 - ys, xs] = STOPPED
    progress = slices.progress(state)
    assert progress[10] == 7 and progress[20] == DONE
    assert (np.delete(progress, [10, 20]) == 6).all()


def test_group_count_rule():
    assert group_count(960 * 540, 2) == 8
    assert group_count(3840 * 2160, 100) == 256
    assert group_count(64 * 48, 2) == 2  # groups of at least 1024 pixels
    assert group_count(10, 4) == 1

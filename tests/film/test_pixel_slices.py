"""Pixel slices (renderer/film/pixel_slices.py): a round of ROUND_SLICES slices visits every pixel once,
its first 4^j slices are the regular grid of spacing CELL / 2^j, and the viewer's fill of pixels a
partial first round has not reached is the same on the device as in numpy."""
import numpy as np
import pytest
import taichi as ti

from renderer.film.band_table import BandTable
from renderer.film.accumulation import Film, FilmState
from renderer.film.pixel_slices import (BANDS, CELL, INTERLEAVED, PAIR_PIXELS, PREVIEW_SLICES, ROUND_SLICES,
                                   band_order_rows, bayer_matrix, rank_matrix,
                                   filled_mean_array, interleaved_layout, pass_length, slice_mask, slice_pixel,
                                   spp_text)
from renderer.output.tonemap import display_array, tonemap_into


def test_the_slice_order_is_a_permutation_whose_prefixes_are_regular_grids():
    for ranks in (bayer_matrix(), rank_matrix()):
        assert sorted(ranks.ravel().tolist()) == list(range(ROUND_SLICES))
        for j in range(5):  # 1, 4, 16, 64, 256 slices
            spacing = CELL >> j
            grid = np.zeros((CELL, CELL), bool)
            grid[::spacing, ::spacing] = True
            np.testing.assert_array_equal(ranks < 4 ** j, grid)


def test_after_the_preview_a_pass_takes_whole_rows_of_each_cell():
    """Past the spacing-2 grid a round fills each cell row pair by row pair (a pass over a few
    slices touches a few rows of a cell, not all sixteen: renderer/film/pixel_slices.py), the pairs in
    bit-reversed order so the image refines evenly."""
    ranks = rank_matrix()
    np.testing.assert_array_equal(ranks < PREVIEW_SLICES, bayer_matrix() < PREVIEW_SLICES)
    pair_order = []
    for start in range(PREVIEW_SLICES, ROUND_SLICES, PAIR_PIXELS):
        rows = np.unique(np.nonzero((ranks >= start) & (ranks < start + PAIR_PIXELS))[0])
        assert len(rows) == 2 and rows[1] == rows[0] + 1 and rows[0] % 2 == 0
        pair_order.append(rows[0] // 2)
    assert pair_order == [0, 4, 2, 6, 1, 5, 3, 7]


@ti.kernel
def _visit(visits: ti.types.ndarray(), first: ti.i32, count: ti.i32, width: ti.i32, height: ti.i32, order: ti.i32):
    layout = interleaved_layout(count, width)
    for i in range(pass_length(count, width, height, order)):
        x, y = slice_pixel(i, first, count, width, height, order, layout)
        if x < width and y < height:
            ti.atomic_add(visits[height - 1 - y, x], 1)  # row 0 at the top, as the film's arrays


@pytest.mark.parametrize("order", [INTERLEAVED, BANDS], ids=["interleaved", "bands"])
@pytest.mark.parametrize("width, height", [(67, 45), (16, 16), (5, 3), (1, 1), (9, 300), (1000, 20)])
@pytest.mark.parametrize("cuts", [((0, 1), (1, 6), (7, 100), (107, 149)),  # a round cut into unequal passes
                                  ((0, 128), (128, 1), (129, 127))])  # powers of two and either side
def test_passes_over_slices_visit_their_pixels_and_a_round_visits_each_once(width, height, order, cuts):
    total = np.zeros((height, width), np.int32)
    for first, count in cuts:
        visits = np.zeros((height, width), np.int32)
        _visit(visits, first, count, width, height, order)
        np.testing.assert_array_equal(visits, slice_mask(first, count, width, height, order)[::-1].astype(np.int32))
        total += visits
    np.testing.assert_array_equal(total, 1)
    whole = np.zeros((height, width), np.int32)
    _visit(whole, 0, ROUND_SLICES, width, height, order)  # a whole round, in raster order
    np.testing.assert_array_equal(whole, 1)


@ti.kernel
def _visit_banded(visits: ti.types.ndarray(), table: ti.template(), first: ti.i32, count: ti.i32, width: ti.i32):
    for i in range(table.pass_length(first, count, width)):
        x, y = table.pixel(i, first, width)
        ti.atomic_add(visits[visits.shape[0] - 1 - y, x], 1)


@pytest.mark.parametrize("height", [1, 3, 255, 256, 257, 300, 540])
def test_band_order_lists_every_row_once_in_slice_order(height):
    rows, starts = band_order_rows(height)
    assert sorted(rows.tolist()) == list(range(height))
    for rank in (0, 1, 77, 255):
        mask = slice_mask(rank, 1, 1, height, BANDS)[::-1, 0]  # row 0 at the top
        np.testing.assert_array_equal(rows[starts[rank]:starts[rank + 1]], np.nonzero(mask)[0])


def test_the_band_table_pass_visits_exactly_its_slices_pixels_once_at_every_height():
    """The render kernel's passes over bands (renderer/film/band_table.py) take exactly the pixels of
    slice_pixel's passes, each once, and a round all of them; the table follows the film's height
    as it changes (a smaller internal resolution, then back)."""
    table = BandTable(300)
    width = 9
    for height in (300, 45, 1, 256, 300):
        table.set_height(height)
        total = np.zeros((height, width), np.int32)
        for first, count in ((0, 1), (1, 6), (7, 100), (107, 148), (255, 1)):
            visits = np.zeros((height, width), np.int32)
            _visit_banded(visits, table, first, count, width)
            np.testing.assert_array_equal(visits, slice_mask(first, count, width, height, BANDS)[::-1].astype(np.int32))
            total += visits
        np.testing.assert_array_equal(total, 1)
    with pytest.raises(ValueError, match="height 301"):
        table.set_height(301)


def test_bands_are_whole_rows_spread_over_the_image():
    width, height = 7, 512  # two rows a band
    for rank, band in ((0, 0), (1, 128), (2, 64), (3, 192), (255, 255)):  # band = rank's 8 bits reversed
        mask = slice_mask(rank, 1, width, height, BANDS)[::-1]  # row 0 at the top
        np.testing.assert_array_equal(np.nonzero(mask.any(axis=1))[0], [2 * band, 2 * band + 1])
        assert mask[2 * band:2 * band + 2].all()
    # The first 2^k slices of a round are bands evenly spaced over the image.
    for k in range(1, 9):
        tops = np.nonzero(slice_mask(0, 2**k, width, height, BANDS)[::-1][:, 0])[0][::2]
        assert np.all(np.diff(tops) == height // 2**k)


def test_the_display_fills_unreached_pixels_from_the_nearest_sampled_grid_point():
    """A film whose first round stopped after 9 slices: the tone-mapped display (device) equals the
    numpy fill, and no displayed pixel is black although most were never sampled."""
    width, height = 37, 21
    rng = np.random.default_rng(3)
    reached = slice_mask(0, 9, width, height)[::-1]  # film rows: row 0 at the top
    mean = np.where(reached[..., None], rng.uniform(0.2, 2.0, (height, width, 3)), 0.0).astype(np.float32)
    count = reached.astype(np.int32)
    film = Film(width, height)
    film.restore(FilmState(mean, np.zeros_like(mean), count, np.zeros_like(count)))
    out = np.zeros((width, height, 3), np.float32)
    tonemap_into(film, out, 0.0, "aces")
    expected = display_array(filled_mean_array(mean, count), 0.0, "aces")  # (H, W, 3), row 0 at the top
    shown = np.transpose(out, (1, 0, 2))[::-1]
    np.testing.assert_allclose(shown, expected, atol=1e-5)  # the kernel and its numpy twin, in f32
    assert (shown.max(axis=2) > 0).all() and reached.mean() < 0.05


def test_a_full_film_is_shown_as_it_is():
    mean = np.random.default_rng(4).uniform(0, 1, (6, 9, 3)).astype(np.float32)
    np.testing.assert_array_equal(filled_mean_array(mean, np.ones((6, 9), np.int32)), mean)


def test_spp_text():
    assert spp_text(64) == "64" and spp_text(12.25) == "12.25" and spp_text(9 / ROUND_SLICES) == "0.0352"

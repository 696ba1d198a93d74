"""The rows of a round cut into bands (pixel_slices.BANDS), in slice order, on the device.

The viewer's still frames render their passes over bands of rows. Mapping a loop index to its
pixel by pixel_slices.slice_pixel's arithmetic costs a few integer divisions by run-time values a
pixel, and a band pass there has the loop indices of the tallest band for each (3 rows at 540,
2.1 on average: the rest compute a pixel only to skip it). Against a whole round in one launch, a
round in two passes (255 slices and 1) then cost 4.6 % more on the Cornell box / mis at 960x540
on two cores (3.7 % at 960x512, where every band has two rows). With this table a pass visits
exactly its rows, one division a pixel, as a whole round does: the same pixels, the same samples,
only their loop indices differ.
"""
import numpy as np
import taichi as ti

from renderer.film.pixel_slices import (BANDS, ROUND_SLICES, band_order_rows, interleaved_layout, pass_length,
                                         slice_pixel)


@ti.data_oriented
class BandTable:
    """rows[k]: the film row (y up) of the k-th row of a round in BANDS slice order; starts[r]: the
    index in `rows` of slice r's first row (starts[ROUND_SLICES] = the height)."""

    def __init__(self, max_height: int):
        self.rows = ti.field(ti.i32, shape=max_height)
        self.starts = ti.field(ti.i32, shape=ROUND_SLICES + 1)
        self.height = -1
        # Filled now, with its tallest image: the first fill compiles the uploads (~90 ms on two
        # cores), which belongs with the scene's loading, not with the first still frame's pass.
        self.set_height(max_height)

    def set_height(self, height: int) -> None:
        """Fill the table for an image `height` rows tall (nothing to do when it already is)."""
        if height == self.height:
            return
        if not 0 < height <= self.rows.shape[0]:
            raise ValueError(f"band table: height {height} outside 1..{self.rows.shape[0]}")
        rows, starts = band_order_rows(height)
        table = np.zeros(self.rows.shape[0], np.int32)
        table[:height] = height - 1 - rows  # rows count from the top; the film's y counts up
        self.rows.from_numpy(table)
        self.starts.from_numpy(starts)
        self.height = height

    @ti.func
    def pass_length(self, slice_first, slice_count, width):
        """Loop indices of a pass over slices [slice_first, slice_first + slice_count): its pixels."""
        return (self.starts[slice_first + slice_count] - self.starts[slice_first]) * width

    @ti.func
    def pixel(self, i, slice_first, width):
        """(x, y) of loop index i of that pass: its rows in slice order, each left to right."""
        k = i // width
        return i - k * width, self.rows[self.starts[slice_first] + k]


@ti.func
def pass_layout(bands: ti.template(), slice_first, slice_count, width, height, order):
    """(banded, layout, loop indices) of a render pass over slices [slice_first, slice_first +
    slice_count): a partial pass over bands visits its rows from the table (the same pixels as
    slice_pixel's, without its divisions and skipped indices); any other pass maps its indices
    with slice_pixel and the interleaved layout."""
    banded = order == BANDS and slice_count < ROUND_SLICES
    layout = interleaved_layout(slice_count, width)
    n = bands.pass_length(slice_first, slice_count, width) if banded else pass_length(slice_count, width, height, order)
    return banded, layout, n


@ti.func
def pass_pixel(bands: ti.template(), i, banded, slice_first, slice_count, width, height, order, layout):
    """The pixel (x, y) of loop index i of that pass (outside the film for padding indices)."""
    x = 0
    y = 0
    if banded:
        x, y = bands.pixel(i, slice_first, width)
    else:
        x, y = slice_pixel(i, slice_first, slice_count, width, height, order, layout)
    return x, y

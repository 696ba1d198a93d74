"""How per-pixel fields (film, AOVs, work, adaptive sampling's errors) are laid out in memory.

Indexed [x, y] like every image field here, but stored with x varying fastest (order "ji"): the
render kernel visits pixels in rows (pixel_slices: whole rounds in raster order, partial passes
cell by cell), so neighbouring loop indices touch neighbouring memory. Taichi's default keeps y
fastest, which put consecutive pixels of a row one column of the allocation apart (2 KB for an
i32 field at 960x540, a new cache line and often a new page for each of the eight fields a sample
touches). Measured in one process, layouts alternated (Cornell box, path, 960x540, two threads,
median of 5): a whole round cost 0.996 ms a slice with y fastest, 0.846 with x fastest; passes of
16 slices 1.320 against 1.169. Loops over these fields go row by row (y outer, x inner) to match.
"""
import numpy as np
import taichi as ti

PIXEL_ORDER = "ji"  # x fastest


def pixel_scalar(dtype, shape: tuple[int, int]):
    """A per-pixel scalar field of `shape` (width, height), x varying fastest in memory."""
    return ti.field(dtype, shape=shape, order=PIXEL_ORDER)


def pixel_vector(n: int, dtype, shape: tuple[int, int]):
    """A per-pixel n-vector field of `shape` (width, height), x varying fastest in memory."""
    return ti.Vector.field(n, dtype, shape=shape, order=PIXEL_ORDER)


@ti.kernel
def _row_sums(field: ti.template(), width: ti.i32, height: ti.i32, out: ti.types.ndarray(dtype=ti.f32, ndim=2)):
    for y in range(height):
        for c in ti.static(range(field.n)):
            total = 0.0
            for x in range(width):
                total += field[x, y][c]
            out[y, c] = total


def row_sums(field, width: int, height: int):
    """Per-row sums, float32 (height, n), of a per-pixel n-vector field's [0:width, 0:height]:
    a reduction on the device (a row of f32 sums keeps ~7 digits), the rows summed in float64 by
    the caller. Downloading the field to sum it took ~35 ms at 960x540, a frame of the viewer."""
    out = np.zeros((height, field.n), np.float32)
    _row_sums(field, width, height, out)
    return out

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
import taichi as ti

PIXEL_ORDER = "ji"  # x fastest


def pixel_scalar(dtype, shape: tuple[int, int]):
    """A per-pixel scalar field of `shape` (width, height), x varying fastest in memory."""
    return ti.field(dtype, shape=shape, order=PIXEL_ORDER)


def pixel_vector(n: int, dtype, shape: tuple[int, int]):
    """A per-pixel n-vector field of `shape` (width, height), x varying fastest in memory."""
    return ti.Vector.field(n, dtype, shape=shape, order=PIXEL_ORDER)

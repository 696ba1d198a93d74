"""Pixel slices: a sample per pixel split into ROUND_SLICES interleaved parts that cover the image evenly.

The image is cut into CELL x CELL cells; slice r of a round is the pixel at the same offset in
every cell, offsets taken in the order of a CELL x CELL Bayer (ordered-dither) matrix. The first
4^j slices of a round are then the regular grid of spacing CELL / 2^j, so a frame that renders
only a few slices still samples the whole image evenly, and an image whose round is unfinished
can show every pixel from the nearest finer-or-equal grid point already reached (`anchor`).

A pixel's sample index is its own count of samples so far (the film's accepted plus rejected
counts), not a global counter: pixels may be one sample apart within a round, and a pixel's
sequence of samples is the same however the rounds were cut into passes. A render is therefore
bit-identical whatever slices its passes took (frames of the viewer, chunks of `render`, a
resumed checkpoint).

A round may also be cut into bands of rows (BANDS): slice r is the rows [r h / ROUND_SLICES,
(r + 1) h / ROUND_SLICES) counted from the top, so a pass over a few slices is a block of whole
rows, visited in raster order. The viewer renders its still frames so after the first round
(which keeps the interleaved order: an image refining evenly from a coarse one): a partial pass
over interleaved slices costs more per sample than the same pixels as rows (their neighbours in
the loop are 2-16 pixels apart, in memory and in the scene), measured in one process, passes of
one 40 ms frame's slices alternated: bunnies / mis 1.33x, textured / mis 1.53x, pool / mis 1.14x,
Cornell box / path 1.03x, showcase / path 1.02x. Which pixels a pass takes never changes their
values (each continues at its own sample index), so either order gives the same film; an order
is a property of a render, and everything that maps its slices to pixels (the display's partial
redraws) is told which.
"""
import numpy as np
import taichi as ti

CELL_BITS = 4
CELL = 1 << CELL_BITS  # cells of 16 x 16 pixels
ROUND_SLICES = CELL * CELL  # 256 slices make one sample per pixel
INTERLEAVED = 0  # slice r: the pixel of Bayer rank r in every CELL x CELL cell
BANDS = 1  # slice r: a band of whole rows (band_start)


@ti.func
def slice_offset(rank):
    """(x, y) in the cell of slice `rank` in [0, ROUND_SLICES): the inverse of the Bayer matrix
    B(x, y) = bit_reverse(interleave(x ^ y, y)) (x ^ y on the odd bits, y on the even bits)."""
    reversed_rank = 0
    for b in ti.static(range(2 * CELL_BITS)):
        reversed_rank |= ((rank >> b) & 1) << (2 * CELL_BITS - 1 - b)
    x = 0
    y = 0
    for i in ti.static(range(CELL_BITS)):
        y_bit = (reversed_rank >> (2 * i)) & 1
        x_bit = ((reversed_rank >> (2 * i + 1)) & 1) ^ y_bit
        x |= x_bit << i
        y |= y_bit << i
    return x, y


@ti.func
def band_start(rank, height):
    """The first row, counted from the top, of band `rank` (BANDS); band_start(ROUND_SLICES) = height."""
    return rank * height // ROUND_SLICES


@ti.func
def slice_pixel(i, slice_first, slice_count, width, height, order=INTERLEAVED):
    """The pixel (x, y) of loop index i of a pass over slices [slice_first, slice_first + slice_count).

    A whole round (slice_count == ROUND_SLICES) visits the pixels in raster order (neighbouring
    loop indices are neighbouring pixels, as a plain full pass); a partial one visits cell after
    cell, each cell's pixels of those slices together (neighbouring loop indices lie within one
    16x16 cell: taking each slice across the image in turn instead, the Cornell box's rays lost
    their coherence and a pass of 255 slices cost 1.02 ms a slice against a whole round's 0.81 at
    960x540 on two threads). (x, y) may fall outside the image in a partial pass (the last row
    and column of cells are cut by the image's edge): callers skip those. With `order` BANDS a
    partial pass is its bands' rows, top to bottom, each left to right.
    """
    x = 0
    y = 0
    if slice_count >= ROUND_SLICES:
        x = i % width
        y = i // width
    elif order == BANDS:
        x = i % width
        y = height - 1 - (band_start(slice_first, height) + i // width)
    else:
        cells_x = (width + CELL - 1) >> CELL_BITS
        ox, oy = slice_offset(slice_rank(i, slice_first, slice_count))
        cell = i // slice_count
        x = ((cell % cells_x) << CELL_BITS) + ox
        y = ((cell // cells_x) << CELL_BITS) + oy
    return x, y


@ti.func
def slice_rank(i, slice_first, slice_count):
    """The slice of loop index i of a partial pass (see slice_pixel)."""
    return slice_first + i % slice_count


@ti.func
def pass_length(slice_count, width, height, slice_first=0, order=INTERLEAVED):
    """Loop indices of a pass over `slice_count` slices from `slice_first` (see slice_pixel)."""
    n = width * height
    if slice_count < ROUND_SLICES and order == BANDS:
        n = (band_start(slice_first + slice_count, height) - band_start(slice_first, height)) * width
    elif slice_count < ROUND_SLICES:
        n = slice_count * ((width + CELL - 1) >> CELL_BITS) * ((height + CELL - 1) >> CELL_BITS)
    return n


# --- numpy (tests, and the host's view of which pixels a slice holds) -----------------------------


def bayer_matrix() -> np.ndarray:
    """B[y, x]: the rank of offset (x, y) in a round, CELL x CELL."""
    y, x = np.mgrid[0:CELL, 0:CELL]
    mixed = np.zeros_like(x)
    for i in range(CELL_BITS):
        mixed |= (((x ^ y) >> i) & 1) << (2 * i + 1)
        mixed |= ((y >> i) & 1) << (2 * i)
    reversed_rank = np.zeros_like(mixed)
    for b in range(2 * CELL_BITS):
        reversed_rank |= ((mixed >> b) & 1) << (2 * CELL_BITS - 1 - b)
    return reversed_rank


def slice_mask(slice_first: int, slice_count: int, width: int, height: int, order: int = INTERLEAVED) -> np.ndarray:
    """Boolean (height, width) [row 0 = y 0], True where a pass over those slices samples."""
    if slice_count >= ROUND_SLICES:
        return np.ones((height, width), bool)
    if order == BANDS:
        mask = np.zeros((height, width), bool)
        top_rows = slice(slice_first * height // ROUND_SLICES, (slice_first + slice_count) * height // ROUND_SLICES)
        mask[::-1][top_rows] = True  # bands count rows from the top, the mask's row 0 is y 0
        return mask
    ranks = np.tile(bayer_matrix(), ((height + CELL - 1) // CELL, (width + CELL - 1) // CELL))[:height, :width]
    return (ranks >= slice_first) & (ranks < slice_first + slice_count)


@ti.func
def filled_mean(mean, count, rejected, x, y):
    """The film's mean at (x, y), or, while the round that first reaches it is unfinished, the mean
    at the nearest grid point of the finest spacing (2, 4, ... CELL) already sampled: a partial
    first round shows as a coarse image that refines, never as black holes. The grid points of
    spacing s are the cell offsets that are multiples of s, which the Bayer order reaches first."""
    value = mean[x, y]
    found = count[x, y] + rejected[x, y] > 0
    for k in ti.static(range(1, CELL_BITS + 1)):
        if not found:
            ax = x & ~((1 << k) - 1)
            ay = y & ~((1 << k) - 1)
            if count[ax, ay] + rejected[ax, ay] > 0:
                value = mean[ax, ay]
                found = True
    return value


def filled_mean_array(mean: np.ndarray, samples: np.ndarray) -> np.ndarray:
    """numpy twin of filled_mean over a whole image: mean (H, W, 3) and samples (H, W), row 0 at
    the top as the film returns them (the grid is anchored at the film's bottom-left corner)."""
    mean, samples = mean[::-1], samples[::-1]  # y up, as the film's fields
    height, width = samples.shape
    y, x = np.mgrid[0:height, 0:width]
    out = mean.copy()
    found = samples > 0
    for k in range(1, CELL_BITS + 1):
        mask = ~((1 << k) - 1)
        ay, ax = y & mask, x & mask
        take = ~found & (samples[ay, ax] > 0)
        out[take] = mean[ay[take], ax[take]]
        found |= take
    return out[::-1]


def spp_text(spp: float) -> str:
    """Samples per pixel as shown to users: '64' when whole, '12.34' within a round of slices,
    '0.0352' (three significant digits) within the first."""
    if float(spp).is_integer():
        return f"{spp:.0f}"
    return f"{spp:.2f}" if spp >= 1 else f"{spp:.3g}"

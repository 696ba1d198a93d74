"""Pixel slices: a sample per pixel split into ROUND_SLICES interleaved parts that cover the image evenly.

The image is cut into CELL x CELL cells; slice r of a round is the pixel at the same offset in
every cell (rank_matrix). The first PREVIEW_SLICES offsets are taken in the order of a CELL x CELL
Bayer (ordered-dither) matrix: the first 4^j slices of a round are then the regular grid of
spacing CELL / 2^j (down to 2), so a frame that renders only a few slices still samples the whole
image evenly, and an image whose round is unfinished can show every pixel from the nearest
finer-or-equal grid point already reached (`anchor`). The remaining three quarters fill each
cell by pairs of rows, the pairs in bit-reversed order: a pass over Bayer slices touches every
row of every cell for a few pixels of each (the film's memory in many scattered pieces), one
over row slices a few whole rows of each cell: a first round in one 40 ms frame's passes costs
1.03-1.09x a whole round's launch at 960x540 (`python scripts/slice_order_cost.py`; with Bayer
order throughout 1.07-1.18x; docs/findings.md).

A pixel's sample index is its own count of samples so far (the film's accepted plus rejected
counts), not a global counter: pixels may be one sample apart within a round, and a pixel's
sequence of samples is the same however the rounds were cut into passes. A render is therefore
bit-identical whatever slices its passes took (frames of the viewer, chunks of `render`, a
resumed checkpoint).

A round may also be cut into bands of rows (BANDS): the image's rows, counted from the top, in
ROUND_SLICES bands [b h / ROUND_SLICES, (b + 1) h / ROUND_SLICES), slice r being band
bit_reverse(r). A band is whole rows visited in raster order; the bit reversal spreads the bands
of consecutive slices over the image as the Bayer order spreads its pixels, so a pass over a few
slices meets the scene's cheap and dear rows alike and costs what the image's average says (with
bands taken top to bottom, frames planned at the average ran long over the model: bunnies / mis
p95 input latency 106-120 ms in a `bench interactive` run). The viewer renders its still frames
so after the first round (which keeps the interleaved order: an image refining evenly from a
coarse one): a partial pass over interleaved slices costs more per sample than the same pixels
as rows (their neighbours in the loop are 2-16 pixels apart, in memory and in the scene).
`python scripts/slice_order_cost.py 3 cornell_box/path bunnies/mis textured/mis` (passes of one
40 ms frame's slices, alternated in one process), interleaved / bands: 1.06, 1.38, 1.29. Here a
band pass has the loop indices of the tallest band for each (3 rows at 540, 2.1 on average): the
indices past a band's rows only compute their pixel and skip. The render kernel does not use
that form: it takes a band pass's rows from a table (renderer/film/band_table.py), the same pixels
without the skipped indices and the divisions. Which pixels a pass takes never
changes their values (each continues at
its own sample index), so either order gives the same film; an order is a property of a render,
and everything that maps its slices to pixels (the display's partial redraws) is told which.
"""
import numpy as np
import taichi as ti

CELL_BITS = 4
CELL = 1 << CELL_BITS  # cells of 16 x 16 pixels
ROUND_SLICES = CELL * CELL  # 256 slices make one sample per pixel
# The first PREVIEW_SLICES ranks are the Bayer order's (its prefix: the grid of spacing 2); the
# rest fill a cell's remaining pixels by pairs of rows (PAIR_PIXELS each), the pairs in
# bit-reversed order, so a pass over a few of them touches a few rows of each cell.
PREVIEW_SLICES = ROUND_SLICES // 4
PAIR_BITS = CELL_BITS - 1
PAIR_PIXELS = CELL // 2 + CELL  # the odd columns of the even row, and the odd row
INTERLEAVED = 0  # slice r: the pixel of rank r in every CELL x CELL cell (rank_matrix)
BANDS = 1  # slice r: the band of whole rows bit_reverse(r) (band_start)


@ti.func
def bit_reverse(rank):
    """rank's 2 * CELL_BITS bits reversed (the band of slice `rank` under BANDS)."""
    return bit_reverse_bits(rank, 2 * CELL_BITS)


@ti.func
def slice_offset(rank):
    """(x, y) in the cell of slice `rank` in [0, ROUND_SLICES) (rank_matrix's inverse). Below
    PREVIEW_SLICES: the inverse of the Bayer matrix B(x, y) = bit_reverse(interleave(x ^ y, y))
    (x ^ y on the odd bits, y on the even bits); from there, row pair by row pair."""
    x = 0
    y = 0
    if rank < PREVIEW_SLICES:
        reversed_rank = bit_reverse(rank)
        for i in ti.static(range(CELL_BITS)):
            y_bit = (reversed_rank >> (2 * i)) & 1
            x_bit = ((reversed_rank >> (2 * i + 1)) & 1) ^ y_bit
            x |= x_bit << i
            y |= y_bit << i
    else:
        j = rank - PREVIEW_SLICES
        pair = j // PAIR_PIXELS
        at = j - pair * PAIR_PIXELS
        y = 2 * bit_reverse_bits(pair, PAIR_BITS)
        if at < CELL // 2:
            x = 2 * at + 1
        else:
            x = at - CELL // 2
            y += 1
    return x, y


@ti.func
def bit_reverse_bits(value, bits: ti.template()):
    """The low `bits` bits of value reversed."""
    out = 0
    for b in ti.static(range(bits)):
        out |= ((value >> b) & 1) << (bits - 1 - b)
    return out


@ti.func
def band_start(band, height):
    """The first row, counted from the top, of band `band` (BANDS); band_start(ROUND_SLICES) = height."""
    return band * height // ROUND_SLICES


@ti.func
def band_rows(height):
    """Rows of the tallest band (BANDS)."""
    return (height + ROUND_SLICES - 1) // ROUND_SLICES


@ti.func
def slice_pixel(i, slice_first, slice_count, width, height, order, layout):
    """The pixel (x, y) of loop index i of a pass over slices [slice_first, slice_first + slice_count).

    A whole round (slice_count == ROUND_SLICES) visits the pixels in raster order (neighbouring
    loop indices are neighbouring pixels, as a plain full pass); a partial one visits cell after
    cell, each cell's pixels of those slices together (neighbouring loop indices lie within one
    16x16 cell: taking each slice across the image in turn instead, a pass of 255 slices of the
    Cornell box cost 1.02 ms a slice against a whole round's 0.81 at 960x540 on two threads, with
    the film then stored y fastest: renderer/film/pixel_fields.py). `layout` (interleaved_layout,
    computed once per launch) pads the slices of a cell and the cells of a row to powers of two,
    so a loop index splits into slice, cell column and cell row by shifts and masks: the integer
    divisions by run-time values this took cost a cheap integrator more than its sample (ad hoc,
    scripts/slice_order_cost.py, Cornell box at 960x540, a round in passes of one frame's slices
    against whole-round launches, three runs: normals 1.65 -> 1.05-1.11, path 1.15 -> 1.05-1.09).
    (x, y) falls outside the image for the padding's indices and where the last row and column of
    cells are cut by the image's edge: callers skip those. With `order` BANDS a partial pass
    visits its slices' bands in turn, each row by row, left to right; each band has the loop
    indices of the tallest (band_rows), those beyond its own rows falling outside.
    """
    x = 0
    y = 0
    if slice_count >= ROUND_SLICES:
        x = i % width
        y = i // width
    elif order == BANDS:
        per_band = band_rows(height) * width
        band = bit_reverse(slice_first + i // per_band)
        row = band_start(band, height) + (i % per_band) // width
        x = i % width
        y = height  # outside: a row past this band's own
        if row < band_start(band + 1, height):
            y = height - 1 - row
    else:
        cells_x = (width + CELL - 1) >> CELL_BITS
        rank_bits, cx_bits = layout & 0xFF, layout >> 8
        k = i & ((1 << rank_bits) - 1)
        cell = i >> rank_bits
        cx = cell & ((1 << cx_bits) - 1)
        x = width
        if k < slice_count and cx < cells_x:
            ox, oy = slice_offset(slice_first + k)
            x = (cx << CELL_BITS) + ox
            y = ((cell >> cx_bits) << CELL_BITS) + oy
    return x, y


@ti.func
def interleaved_layout(slice_count, width):
    """A partial interleaved pass's loop index layout (slice_pixel): its rank bits in the low
    byte, its cell-column bits above (one integer: a vector computed before a kernel's parallel
    loop lost pixels on Vulkan)."""
    return ceil_log2(slice_count) | (ceil_log2((width + CELL - 1) >> CELL_BITS) << 8)


@ti.func
def ceil_log2(value):
    """The bits of the smallest power of two at least `value` (1 to 2^16)."""
    bits = 0
    for b in ti.static(range(16)):
        if (1 << b) < value:
            bits = b + 1
    return bits


@ti.func
def slice_rank(i, slice_first, layout):
    """The slice of loop index i of a partial interleaved pass (see slice_pixel)."""
    return slice_first + (i & ((1 << (layout & 0xFF)) - 1))


@ti.func
def pass_length(slice_count, width, height, order=INTERLEAVED):
    """Loop indices of a pass over `slice_count` slices (see slice_pixel)."""
    n = width * height
    if slice_count < ROUND_SLICES and order == BANDS:
        n = slice_count * band_rows(height) * width
    elif slice_count < ROUND_SLICES:
        n = ((height + CELL - 1) >> CELL_BITS) << (ceil_log2((width + CELL - 1) >> CELL_BITS) + ceil_log2(slice_count))
    return n


# --- numpy (tests, and the host's view of which pixels a slice holds) -----------------------------


def bit_reverse_array(ranks: np.ndarray, bits: int = 2 * CELL_BITS) -> np.ndarray:
    """numpy twin of bit_reverse_bits (by default bit_reverse's 8 bits)."""
    ranks = np.asarray(ranks)
    out = np.zeros_like(ranks)
    for b in range(bits):
        out |= ((ranks >> b) & 1) << (bits - 1 - b)
    return out


def band_rows_array(bands: np.ndarray, height: int) -> tuple[np.ndarray, np.ndarray]:
    """numpy twin of band_start: the rows [start, end) from the top of each band under BANDS."""
    bands = np.asarray(bands)
    return bands * height // ROUND_SLICES, (bands + 1) * height // ROUND_SLICES


def band_order_rows(height: int) -> tuple[np.ndarray, np.ndarray]:
    """BANDS' rows in slice order: (rows, starts), rows[starts[r]:starts[r + 1]] being slice r's
    band, its rows counted from the top, top to bottom (renderer/film/band_table.py keeps it on the
    device for the render kernel's passes)."""
    top, bottom = band_rows_array(bit_reverse_array(np.arange(ROUND_SLICES)), height)
    rows = np.concatenate([np.arange(t, b) for t, b in zip(top, bottom)]).astype(np.int32)
    starts = np.concatenate([[0], np.cumsum(bottom - top)]).astype(np.int32)
    return rows, starts


def bayer_matrix() -> np.ndarray:
    """B[y, x]: the rank of offset (x, y) in the CELL x CELL Bayer (ordered-dither) order."""
    y, x = np.mgrid[0:CELL, 0:CELL]
    mixed = np.zeros_like(x)
    for i in range(CELL_BITS):
        mixed |= (((x ^ y) >> i) & 1) << (2 * i + 1)
        mixed |= ((y >> i) & 1) << (2 * i)
    return bit_reverse_array(mixed)


def rank_matrix() -> np.ndarray:
    """R[y, x]: the rank (slice) of offset (x, y) in a round, CELL x CELL: the Bayer rank where it
    is below PREVIEW_SLICES, then the remaining offsets row pair by row pair (slice_offset)."""
    ranks = bayer_matrix()
    rank = PREVIEW_SLICES
    for pair in range(CELL // 2):
        y = 2 * int(bit_reverse_array(np.array(pair), PAIR_BITS))
        for x in range(1, CELL, 2):
            ranks[y, x] = rank
            rank += 1
        for x in range(CELL):
            ranks[y + 1, x] = rank
            rank += 1
    return ranks


def rank_image(width: int, height: int) -> np.ndarray:
    """(height, width) [row 0 = y 0]: each pixel's rank (slice) in a round, rank_matrix tiled."""
    return np.tile(rank_matrix(), (-(-height // CELL), -(-width // CELL)))[:height, :width]


def slice_mask(slice_first: int, slice_count: int, width: int, height: int, order: int = INTERLEAVED) -> np.ndarray:
    """Boolean (height, width) [row 0 = y 0], True where a pass over those slices samples."""
    if slice_count >= ROUND_SLICES:
        return np.ones((height, width), bool)
    if order == BANDS:
        mask = np.zeros((height, width), bool)
        from_top = mask[::-1]  # bands count rows from the top, the mask's row 0 is y 0
        for top, bottom in zip(*band_rows_array(bit_reverse_array(np.arange(slice_first, slice_first + slice_count)),
                                                height)):
            from_top[top:bottom] = True
        return mask
    ranks = rank_image(width, height)
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

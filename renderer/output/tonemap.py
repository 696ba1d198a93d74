"""Linear radiance -> display values: exposure, a tone mapper, then the sRGB OETF.

The same pipeline exists twice, as Taichi funcs for the viewer and as float32 numpy for the
command line; tests keep the two in agreement. Non-finite input never reaches the output:
NaN and -inf become 0, +inf becomes the brightest representable radiance (white).
"""

import numpy as np
import taichi as ti

from renderer.film.accumulation import is_finite_f32
from renderer.film.pixel_slices import (CELL, CELL_BITS, INTERLEAVED, ROUND_SLICES, filled_mean, interleaved_layout,
                                   pass_length, slice_pixel, slice_rank)
from renderer.scene.srgb import srgb_oetf_array  # noqa: F401 (the numpy mirror of the kernels' curve)
from renderer.spectral.luminance import LUMINANCE_WEIGHTS, luminance

TONEMAPPERS = ("aces", "reinhard", "none")

# Linear radiance is clamped to [0, MAX_RADIANCE] after exposure: far above where every mapper
# saturates, yet small enough that the ACES rational fit (v * v) stays finite in f32.
MAX_RADIANCE = 1.0e6

# Stephen Hill's fit of the ACES RRT+ODT (BakingLab, ACES.hlsl): sRGB -> ACES-ish input matrix,
# rational curve, and the output matrix back to linear sRGB.
ACES_INPUT = np.array(
    [[0.59719, 0.35458, 0.04823], [0.07600, 0.90834, 0.01566], [0.02840, 0.13383, 0.83777]],
    dtype=np.float32,
)
ACES_OUTPUT = np.array(
    [[1.60475, -0.53108, -0.07367], [-0.10208, 1.10813, -0.00605], [-0.00327, -0.07276, 1.07602]],
    dtype=np.float32,
)

# Plain nested lists: the Taichi funcs build compile-time constant matrices from them.
_ACES_INPUT_ROWS = ACES_INPUT.tolist()
_ACES_OUTPUT_ROWS = ACES_OUTPUT.tolist()


def tonemapper_index(name: str) -> int:
    try:
        return TONEMAPPERS.index(name)
    except ValueError:
        raise ValueError(f"unknown tone mapper '{name}' (expected one of {', '.join(TONEMAPPERS)})") from None


def exposure_scale(exposure_ev: float) -> float:
    return float(np.float32(2.0 ** float(exposure_ev)))


# --- Taichi -------------------------------------------------------------------------------------


@ti.func
def sanitize_radiance(rgb):
    result = ti.math.vec3(0.0)
    for c in ti.static(range(3)):
        value = rgb[c]
        if is_finite_f32(value):
            result[c] = ti.math.clamp(value, 0.0, MAX_RADIANCE)
        elif ti.bit_cast(value, ti.i32) == 0x7F800000:  # +inf; NaN and -inf stay 0
            result[c] = MAX_RADIANCE
    return result


@ti.func
def srgb_oetf(linear):
    encoded = 12.92 * linear
    if linear > 0.0031308:
        encoded = 1.055 * ti.pow(linear, 1.0 / 2.4) - 0.055
    return encoded


@ti.func
def aces_fitted(rgb):
    v = ti.Matrix(_ACES_INPUT_ROWS, ti.f32) @ rgb
    curve = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081)
    return ti.math.clamp(ti.Matrix(_ACES_OUTPUT_ROWS, ti.f32) @ curve, 0.0, 1.0)


@ti.func
def reinhard_luminance(rgb):
    # L -> L / (1 + L), applied as a common scale so hue is kept.
    return ti.math.clamp(rgb / (1.0 + luminance(rgb)), 0.0, 1.0)


@ti.func
def display_value(linear, mapper):
    """Exposed, sanitized linear radiance -> display value in [0, 1]."""
    mapped = ti.math.clamp(linear, 0.0, 1.0)
    if mapper == 0:
        mapped = aces_fitted(linear)
    elif mapper == 1:
        mapped = reinhard_luminance(linear)
    out = ti.math.vec3(0.0)
    for c in ti.static(range(3)):
        out[c] = ti.math.clamp(srgb_oetf(mapped[c]), 0.0, 1.0)
    return out


@ti.func
def _film_radiance(mean, count, rejected, x, y, filled):
    """The film's sanitized mean at (x, y); with `filled` (a first round unfinished), a pixel not
    reached yet shows its nearest sampled grid point (renderer/pixel_slices.filled_mean). After
    the first round every pixel has a sample, and the plain lookup gives the same value."""
    value = ti.math.vec3(0.0)
    if filled:
        value = filled_mean(mean, count, rejected, x, y)
    else:
        value = mean[x, y]
    return sanitize_radiance(value)


@ti.func
def _display_at(mean, count, rejected, x, y, out_width, out_height, source_width, source_height, scale,
                mapper, filled):
    """The display value of output pixel (x, y): the film's active region stretched over the
    output with bilinear filtering of the exposed linear radiance."""
    linear = ti.math.vec3(0.0)
    if out_width == source_width and out_height == source_height:
        # 1:1: the bilinear weights below would be exactly (1, 0, 0, 0); one lookup, same value.
        linear = _film_radiance(mean, count, rejected, x, y, filled)
    else:
        step_x = ti.cast(source_width, ti.f32) / ti.cast(out_width, ti.f32)
        step_y = ti.cast(source_height, ti.f32) / ti.cast(out_height, ti.f32)
        # Pixel centres map to pixel centres.
        sx = ti.math.clamp((ti.cast(x, ti.f32) + 0.5) * step_x - 0.5, 0.0, ti.cast(source_width - 1, ti.f32))
        sy = ti.math.clamp((ti.cast(y, ti.f32) + 0.5) * step_y - 0.5, 0.0, ti.cast(source_height - 1, ti.f32))
        x0 = ti.cast(ti.floor(sx), ti.i32)
        y0 = ti.cast(ti.floor(sy), ti.i32)
        x1 = ti.min(x0 + 1, source_width - 1)
        y1 = ti.min(y0 + 1, source_height - 1)
        fx = sx - ti.cast(x0, ti.f32)
        fy = sy - ti.cast(y0, ti.f32)
        m00 = _film_radiance(mean, count, rejected, x0, y0, filled)
        m10 = _film_radiance(mean, count, rejected, x1, y0, filled)
        m01 = _film_radiance(mean, count, rejected, x0, y1, filled)
        m11 = _film_radiance(mean, count, rejected, x1, y1, filled)
        bottom = m00 * (1.0 - fx) + m10 * fx
        top = m01 * (1.0 - fx) + m11 * fx
        linear = bottom * (1.0 - fy) + top * fy
    return display_value(ti.math.clamp(linear * scale, 0.0, MAX_RADIANCE), mapper)


@ti.func
def pack_rgba8(display):
    """Display values in [0, 1] as the u32 GGUI's canvas takes: R in the low byte, then G, B, and
    alpha 255; each channel rounded to nearest as `quantize` does."""
    packed = ti.cast(255, ti.u32) << 24
    for c in ti.static(range(3)):
        scaled = display[c] * 255.0
        packed |= ti.cast(ti.floor(scaled + 0.5), ti.u32) << (8 * c)
    return packed


@ti.kernel
def _tonemap_kernel(
    mean: ti.template(), count: ti.template(), rejected: ti.template(),
    out: ti.types.ndarray(dtype=ti.math.vec3, ndim=2), source_width: ti.i32, source_height: ti.i32, scale: ti.f32,
    mapper: ti.i32, filled: ti.i32,
):
    for x, y in ti.ndrange(out.shape[0], out.shape[1]):
        out[x, y] = _display_at(mean, count, rejected, x, y, out.shape[0], out.shape[1], source_width, source_height,
                                scale, mapper, filled)


@ti.func
def fill_block_side(rank):
    """Side of the block of pixels that show the pixel of slice `rank` while the first round is
    incomplete. filled_mean shows a pixel not reached yet as the corner of its 2x2, 4x4, ... block,
    the finest one sampled; the Bayer order reaches all corners of 2^k blocks (the first 4^(4-k)
    slices) before any finer point. So the pixel of slice `rank` is the corner of a block of side
    CELL >> ceil(log4(rank + 1)) (the whole cell for slice 0, 8x8 for 1-3, 4x4 for 4-15, 2x2 for
    16-63, itself from 64 on), and sampling it changes exactly that block's displayed pixels: those
    of its finer points are not reached yet."""
    side = CELL
    for j in ti.static(range(CELL_BITS)):
        if rank >= 4 ** j:
            side = CELL >> (j + 1)
    return side


@ti.kernel
def _tonemap_packed_kernel(
    mean: ti.template(), count: ti.template(), rejected: ti.template(),
    out: ti.types.ndarray(dtype=ti.u32, ndim=2), source_width: ti.i32, source_height: ti.i32,
    slice_first: ti.i32, slice_count: ti.i32, order: ti.i32, scale: ti.f32, mapper: ti.i32, filled: ti.i32,
    blocks: ti.i32,
):
    # The output's pixels in pixel-slice order: a whole round is every pixel (raster order), a
    # partial one only the pixels of those slices (1:1 with the film, the ones a render of the
    # same slices changed), with `blocks` (a first round) each one's fill block.
    out_width, out_height = out.shape[0], out.shape[1]
    layout = interleaved_layout(slice_count, out_width)
    for i in range(pass_length(slice_count, out_width, out_height, order)):
        x, y = slice_pixel(i, slice_first, slice_count, out_width, out_height, order, layout)
        side = 1
        if blocks:
            side = fill_block_side(slice_rank(i, slice_first, layout))  # the loop index's slice
        for dy, dx in ti.ndrange(side, side):
            qx, qy = x + dx, y + dy
            if qx < out_width and qy < out_height:
                out[qx, qy] = pack_rgba8(_display_at(mean, count, rejected, qx, qy, out_width, out_height,
                                                     source_width, source_height, scale, mapper, filled))


def tonemap_into(film, out: np.ndarray, exposure_ev: float, tonemapper_name: str, filled: bool = True) -> None:
    """Fill `out` (float32 (width, height, 3), [x, y] y-up) with display values in [0, 1].

    The film's active region (film.width x film.height) is stretched over the whole array with
    bilinear filtering of the exposed linear radiance. With `filled`, pixels a partial first round
    has not reached show their nearest sampled grid point (renderer/pixel_slices.filled_mean);
    without, their own (empty) mean: the same image once the first round is complete. The output
    is an array argument, not a field: one compiled kernel per film serves every output size (a
    field argument would compile the kernel again for each display size, ~0.1 s apiece).
    """
    _tonemap_kernel(
        film.mean, film.count, film.rejected, out, film.width, film.height,
        exposure_scale(exposure_ev), tonemapper_index(tonemapper_name), int(filled),
    )


def tonemap_packed(film, out: np.ndarray, exposure_ev: float, tonemapper_name: str, filled: bool = True,
                   slices: tuple[int, int] | None = None, first_round: bool = False, order: int = INTERLEAVED) -> None:
    """Fill `out` (uint32 (width, height), [x, y] y-up) with the display image packed as RGBA8
    (pack_rgba8): the bytes of quantize(tonemap_into(...)), in the layout GGUI's canvas shows
    without a conversion of its own.

    slices = (first, count) within a round (count < ROUND_SLICES): only the pixels of those pixel
    slices, for an output the film's size; the rest of `out` is left as it is. A viewer whose
    film gained those slices since `out` was filled updates it so at a fraction of the cost.
    With `first_round` (those slices belong to the film's first round), each slice's pixel brings
    its fill block (fill_block_side): the pixels shown filled from it. `order`: how the round the
    slices belong to was cut (pixel_slices: INTERLEAVED, or BANDS after a first round).
    """
    first, count = (0, ROUND_SLICES) if slices is None else (int(slices[0]), int(slices[1]))
    if count < ROUND_SLICES and out.shape[:2] != (film.width, film.height):
        raise ValueError(f"a partial update needs an output of the film's size {film.width}x{film.height}, "
                         f"got {out.shape[0]}x{out.shape[1]}")
    if not (0 <= first and 0 < count and (count >= ROUND_SLICES or first + count <= ROUND_SLICES)):
        raise ValueError(f"slices ({first}, {count}) are not a range within a round of {ROUND_SLICES}")
    _tonemap_packed_kernel(
        film.mean, film.count, film.rejected, out, film.width, film.height, first, count, int(order),
        exposure_scale(exposure_ev), tonemapper_index(tonemapper_name), int(filled),
        int(first_round and count < ROUND_SLICES and order == INTERLEAVED),
    )


def unpack_rgba8(packed: np.ndarray) -> np.ndarray:
    """A packed display image (uint32 (width, height) [x, y] y-up) as uint8 (height, width, 3), row
    0 at the top: the pixels the canvas shows."""
    channels = np.ascontiguousarray(packed, dtype=np.uint32).view(np.uint8).reshape(*packed.shape, 4)
    return np.ascontiguousarray(np.transpose(channels[:, :, :3], (1, 0, 2))[::-1])


# --- numpy (float32, mirrors the Taichi code) ---------------------------------------------------


def display_array(linear_rgb: np.ndarray, exposure_ev: float, name: str) -> np.ndarray:
    """Linear RGB (..., 3) -> display values in [0, 1], float32; same maths as the kernel."""
    mapper = tonemapper_index(name)
    rgb = np.asarray(linear_rgb, dtype=np.float32)
    with np.errstate(invalid="ignore", over="ignore"):
        rgb = np.nan_to_num(rgb, nan=0.0, posinf=MAX_RADIANCE, neginf=0.0)
        rgb = np.clip(rgb, 0.0, MAX_RADIANCE) * np.float32(exposure_scale(exposure_ev))
        rgb = np.clip(rgb, 0.0, MAX_RADIANCE).astype(np.float32)
    if mapper == 0:
        v = rgb @ ACES_INPUT.T
        curve = (v * (v + np.float32(0.0245786)) - np.float32(0.000090537)) / (
            v * (np.float32(0.983729) * v + np.float32(0.4329510)) + np.float32(0.238081)
        )
        mapped = np.clip(curve @ ACES_OUTPUT.T, 0.0, 1.0)
    elif mapper == 1:
        luminance = rgb @ np.array(LUMINANCE_WEIGHTS, dtype=np.float32)
        mapped = np.clip(rgb / (np.float32(1.0) + luminance)[..., None], 0.0, 1.0)
    else:
        mapped = np.clip(rgb, 0.0, 1.0)
    return np.clip(srgb_oetf_array(mapped), 0.0, 1.0).astype(np.float32)


def quantize(display: np.ndarray) -> np.ndarray:
    """Display values in [0, 1] -> uint8 with round-to-nearest."""
    return np.floor(np.clip(display, 0.0, 1.0) * np.float32(255.0) + np.float32(0.5)).astype(np.uint8)


def tonemap_array(linear_rgb: np.ndarray, exposure_ev: float, name: str) -> np.ndarray:
    """Linear RGB (H, W, 3) -> uint8 display image (H, W, 3) for writing PNGs."""
    return quantize(display_array(linear_rgb, exposure_ev, name))

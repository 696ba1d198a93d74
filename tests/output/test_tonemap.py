import numpy as np
import pytest
import taichi as ti

from renderer.film.accumulation import Film
from renderer.film.pixel_slices import ROUND_SLICES, slice_mask
from renderer.output.tonemap import (
    TONEMAPPERS,
    display_array,
    display_value,
    exposure_scale,
    quantize,
    sanitize_radiance,
    srgb_oetf,
    srgb_oetf_array,
    tonemap_array,
    tonemap_into,
    tonemap_packed,
    tonemapper_index,
    unpack_rgba8,
)


def film_with_image(image_rows_top: np.ndarray, max_size=None) -> Film:
    """A film whose active region holds `image_rows_top` (H, W, 3) as its mean."""
    height, width = image_rows_top.shape[:2]
    max_width, max_height = max_size or (width, height)
    film = Film(max_width, max_height)
    film.reset(width, height)
    full = np.zeros((max_width, max_height, 3), dtype=np.float32)
    full[:width, :height] = image_rows_top[::-1].transpose(1, 0, 2)  # row-0-top -> [x, y] y-up
    film.mean.from_numpy(full)
    return film


def display_to_rows(display: np.ndarray) -> np.ndarray:
    return display.transpose(1, 0, 2)[::-1]


def kernel_display(linear_rows_top: np.ndarray, exposure_ev: float, name: str) -> np.ndarray:
    height, width = linear_rows_top.shape[:2]
    out = np.zeros((width, height, 3), np.float32)
    tonemap_into(film_with_image(linear_rows_top), out, exposure_ev, name)
    return display_to_rows(out)


@ti.kernel
def oetf_kernel(values: ti.types.ndarray(), out: ti.types.ndarray()):
    for i in range(values.shape[0]):
        out[i] = srgb_oetf(values[i])


@ti.kernel
def pointwise_display(film: ti.template(), out: ti.template(), scale: ti.f32, mapper: ti.i32):
    for x, y in out:
        out[x, y] = display_value(ti.math.clamp(sanitize_radiance(film.mean[x, y]) * scale, 0.0, 1.0e6), mapper)


def srgb_encoded(linear):
    """The sRGB encoding by its definition (IEC 61966-2-1), in float64: 12.92 x up to 0.0031308,
    1.055 x^(1/2.4) - 0.055 above."""
    x = np.asarray(linear, np.float64)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.maximum(x, 0.0031308) ** (1.0 / 2.4) - 0.055)


SRGB_HALF = float(srgb_encoded(0.5))  # 0.7353569831: a display value of 0.5 linear


def test_srgb_oetf_known_values():
    linear = np.array([0.0, 0.001, 0.0031308, 0.18, 0.5, 1.0], dtype=np.float32)
    expected = srgb_encoded(linear).astype(np.float32)  # 0, 0.01292, 0.040449936, 0.4613561295, SRGB_HALF, 1
    out = np.zeros_like(linear)
    oetf_kernel(linear, out)
    np.testing.assert_allclose(out, expected, atol=2e-6)
    np.testing.assert_allclose(srgb_oetf_array(linear), expected, atol=2e-6)


def test_aces_grey_ramp_is_monotonic_from_black_to_white():
    grey = np.geomspace(1e-4, 1e5, 512, dtype=np.float32)
    ramp = np.concatenate([[0.0], grey]).astype(np.float32)
    image = np.repeat(ramp[None, :, None], 3, axis=2)
    display = kernel_display(image, 0.0, "aces")[0]
    assert np.all(np.diff(display, axis=0) >= 0.0)
    assert np.all(display[0] == 0.0)
    assert np.all(display[-1] >= 0.999)
    # Neutral stays neutral: the input matrix rows sum to 1.
    np.testing.assert_allclose(display[:, 0], display[:, 1], atol=2e-3)


def test_none_clamps_and_reinhard_halves_luminance_one():
    image = np.array([[[2.0, -1.0, 0.5], [1.0, 1.0, 1.0]]], dtype=np.float32)
    none = kernel_display(image, 0.0, "none")[0]
    np.testing.assert_allclose(none[0], [1.0, 0.0, SRGB_HALF], atol=2e-6)
    reinhard = kernel_display(image, 0.0, "reinhard")[0]
    np.testing.assert_allclose(reinhard[1], SRGB_HALF, atol=2e-6)  # L=1 -> 1/(1+1)


def test_exposure_is_in_stops():
    assert exposure_scale(1.0) == 2.0 and exposure_scale(-2.0) == 0.25
    image = np.full((1, 1, 3), 0.125, dtype=np.float32)
    np.testing.assert_allclose(kernel_display(image, 2.0, "none"), SRGB_HALF, atol=2e-6)  # 0.125 x 2^2


def test_kernel_and_numpy_agree_and_output_is_finite():
    rng = np.random.default_rng(3)
    image = (rng.lognormal(-1.0, 2.0, size=(17, 23, 3))).astype(np.float32)
    image[0, 0] = [np.nan, 1.0, 1.0]
    image[1, 2] = [np.inf, 0.0, 0.0]
    image[2, 3] = [0.5, -np.inf, 0.2]
    image[3, 4] = [-0.5, 0.3, 3.0e38]
    image[4, 5] = np.inf
    for name in TONEMAPPERS:
        for ev in (-3.0, 0.0, 1.5):
            from_kernel = kernel_display(image, ev, name)
            from_numpy = display_array(image, ev, name)
            assert np.isfinite(from_kernel).all() and np.isfinite(from_numpy).all()
            assert from_kernel.min() >= 0.0 and from_kernel.max() <= 1.0
            np.testing.assert_allclose(from_kernel, from_numpy, atol=1e-5, err_msg=f"{name} ev={ev}")
            bytes_kernel = np.floor(from_kernel * 255.0 + 0.5).astype(np.uint8)
            bytes_numpy = tonemap_array(image, ev, name)
            assert bytes_numpy.dtype == np.uint8 and bytes_numpy.shape == image.shape
            assert np.abs(bytes_kernel.astype(int) - bytes_numpy).max() <= 1
            assert np.mean(bytes_kernel == bytes_numpy) > 0.999
        # +inf is white, NaN is black.
        np.testing.assert_allclose(display_array(image, 0.0, name)[4, 5], 1.0, atol=1e-6)
        np.testing.assert_array_equal(display_array(np.full((1, 1, 3), np.nan), 0.0, name), 0.0)


def test_one_to_one_copy_has_no_blur():
    checker = np.indices((6, 8)).sum(axis=0) % 2
    image = np.where(checker[..., None] == 1, 0.9, 0.01).astype(np.float32) * np.array([1.0, 0.5, 0.25], np.float32)
    film = film_with_image(image, max_size=(10, 9))
    out = np.zeros((8, 6, 3), np.float32)
    reference = ti.Vector.field(3, ti.f32, shape=(8, 6))
    for name in TONEMAPPERS:
        tonemap_into(film, out, 0.5, name)
        pointwise_display(film, reference, exposure_scale(0.5), tonemapper_index(name))
        # Equal up to f32 rounding (two kernels may contract their multiply-adds differently);
        # any blur would mix the checker's 0.9 and 0.01 and be off by orders of magnitude more.
        np.testing.assert_allclose(out, reference.to_numpy(), rtol=1e-6, atol=1e-7)
        np.testing.assert_allclose(display_to_rows(out), display_array(image, 0.5, name), atol=1e-5)


def test_bilinear_upscale_from_half_size_film():
    # A linear ramp is reproduced exactly by bilinear filtering, so the expected value at each
    # window pixel is the ramp evaluated at that pixel's centre mapped into the film.
    width, height = 4, 3
    def ramp(x, y):  # x right, y up, in film pixels
        return 0.05 + 0.1 * x + 0.07 * y

    xs, ys = np.meshgrid(np.arange(width), np.arange(height))
    film_rows = ramp(xs, height - 1 - ys).astype(np.float32)  # row 0 = top = largest y
    film = film_with_image(np.repeat(film_rows[..., None], 3, axis=2), max_size=(8, 8))
    out = np.zeros((2 * width, 2 * height, 3), np.float32)
    tonemap_into(film, out, 0.0, "none")

    window_x, window_y = np.meshgrid(np.arange(2 * width), np.arange(2 * height), indexing="ij")
    source_x = np.clip((window_x + 0.5) / 2 - 0.5, 0, width - 1)
    source_y = np.clip((window_y + 0.5) / 2 - 0.5, 0, height - 1)
    expected_linear = ramp(source_x, source_y).astype(np.float32)  # [x, y]
    expected = srgb_oetf_array(np.clip(expected_linear, 0.0, 1.0))
    result = out
    for c in range(3):
        np.testing.assert_allclose(result[:, :, c], expected, atol=1e-5)


def test_unknown_tonemapper_is_named_in_the_error():
    with pytest.raises(ValueError, match="filmic"):
        tonemap_array(np.zeros((1, 1, 3), np.float32), 0.0, "filmic")


def lognormal_film(width, height, seed, reached=None):
    """A film whose mean is lognormal radiance with a few non-finite pixels; `reached` ([x, y]
    bool) marks the pixels with a sample (default: all)."""
    rng = np.random.default_rng(seed)
    mean = rng.lognormal(-1.0, 2.0, size=(width, height, 3)).astype(np.float32)
    mean[1, 2] = [np.nan, np.inf, -1.0]
    film = Film(width, height)
    film.reset(width, height)
    film.mean.from_numpy(mean)
    film.count.from_numpy(np.ones((width, height), np.int32) if reached is None else reached.astype(np.int32))
    return film


def test_packed_display_is_the_quantized_display_as_rgba8():
    """The packed image the canvas gets holds exactly the bytes `quantize` makes of the float
    display (R in the low byte, alpha 255), at 1:1 and stretched, filled or not."""
    width, height = 37, 21
    rng = np.random.default_rng(11)
    film = lognormal_film(width, height, 4, reached=rng.random((width, height)) < 0.4)
    for name in TONEMAPPERS:
        for size in ((width, height), (18, 10), (74, 42)):
            for filled in (True, False):
                display = np.zeros((*size, 3), np.float32)
                tonemap_into(film, display, 0.7, name, filled=filled)
                packed = np.zeros(size, np.uint32)
                tonemap_packed(film, packed, 0.7, name, filled=filled)
                assert np.all(packed >> 24 == 255)
                np.testing.assert_array_equal(unpack_rgba8(packed), quantize(display_to_rows(display)))


def test_filled_and_plain_lookups_agree_once_every_pixel_is_reached():
    film = lognormal_film(23, 17, 5)
    for size in ((23, 17), (11, 8)):
        filled, plain = np.zeros(size, np.uint32), np.zeros(size, np.uint32)
        tonemap_packed(film, filled, 0.0, "aces", filled=True)
        tonemap_packed(film, plain, 0.0, "aces", filled=False)
        np.testing.assert_array_equal(filled, plain)


def test_a_slice_update_writes_exactly_the_pixels_of_those_slices():
    """A film 3x2 cells and a bit (cut cells at the edges): updating slices (first, count)
    rewrites their pixels as a full update would and leaves every other pixel as it was."""
    width, height = 53, 35
    film = lognormal_film(width, height, 6)
    full = np.zeros((width, height), np.uint32)
    tonemap_packed(film, full, -1.0, "reinhard", filled=False)
    for first, count in ((0, 1), (5, 17), (100, 156), (255, 1)):
        sentinel = np.full((width, height), 0x12345678, np.uint32)
        tonemap_packed(film, sentinel, -1.0, "reinhard", filled=False, slices=(first, count))
        mask = slice_mask(first, count, width, height).T  # [x, y]
        np.testing.assert_array_equal(sentinel[mask], full[mask])
        assert np.all(sentinel[~mask] == 0x12345678)


def test_a_first_round_slice_update_also_writes_the_pixels_shown_filled_from_it():
    """In a first round, slice r's pixel is the corner of the block filled from it: the whole
    16x16 cell for slice 0, 8x8 for 1-3, 4x4 for 4-15, 2x2 for 16-63, the pixel alone after."""
    width, height = 53, 35
    film = lognormal_film(width, height, 8)
    full = np.zeros((width, height), np.uint32)
    tonemap_packed(film, full, 0.0, "aces", filled=True)
    for first, count in ((0, 1), (1, 3), (3, 20), (60, 8)):
        sentinel = np.full((width, height), 0x12345678, np.uint32)
        tonemap_packed(film, sentinel, 0.0, "aces", filled=True, slices=(first, count), first_round=True)
        expected = np.zeros((width, height), bool)
        for rank in range(first, first + count):
            side = 16 if rank == 0 else 8 if rank < 4 else 4 if rank < 16 else 2 if rank < 64 else 1
            for x, y in zip(*np.nonzero(slice_mask(rank, 1, width, height).T)):
                expected[x:x + side, y:y + side] = True
        np.testing.assert_array_equal(sentinel != 0x12345678, expected)
        np.testing.assert_array_equal(sentinel[expected], full[expected])


def test_slice_updates_are_checked():
    film = lognormal_film(16, 16, 7)
    with pytest.raises(ValueError, match="film's size 16x16"):
        tonemap_packed(film, np.zeros((8, 8), np.uint32), 0.0, "aces", slices=(0, 4))
    with pytest.raises(ValueError, match="within a round"):
        tonemap_packed(film, np.zeros((16, 16), np.uint32), 0.0, "aces", slices=(250, 10))
    tonemap_packed(film, np.zeros((8, 8), np.uint32), 0.0, "aces", slices=(0, ROUND_SLICES))  # a full update

import math

import numpy as np
import pytest
import taichi as ti

from renderer.film.accumulation import Film


@ti.kernel
def add_constant(film: ti.template(), value: ti.math.vec3, samples: ti.i32, width: ti.i32, height: ti.i32):
    # One thread per pixel, many samples per launch: the way a renderer pass uses the film.
    for x, y in ti.ndrange(width, height):
        for _ in range(samples):
            film.add_sample(x, y, value)


@ti.kernel
def add_from_array(film: ti.template(), samples: ti.types.ndarray(), width: ti.i32, height: ti.i32):
    # samples[s, x, y, c]
    for x, y in ti.ndrange(width, height):
        for s in range(samples.shape[0]):
            film.add_sample(x, y, ti.math.vec3(samples[s, x, y, 0], samples[s, x, y, 1], samples[s, x, y, 2]))


def test_constant_mean_is_exact_after_a_million_samples():
    film = Film(4, 2)
    for constant in (0.1, 1234.5, 3.0e-5, 7.0):
        film.reset(4, 2)
        value = np.float32(constant)
        add_constant(film, ti.math.vec3(constant, 2 * constant, 0.5 * constant), 1_000_000, 4, 2)
        mean = film.mean_image()
        expected = np.array([value, np.float32(2 * constant), np.float32(0.5 * constant)], dtype=np.float32)
        np.testing.assert_array_equal(mean, np.broadcast_to(expected, mean.shape))
        np.testing.assert_array_equal(film.variance_of_mean_image(), 0.0)
        assert (film.sample_counts() == 1_000_000).all()


def test_non_finite_samples_are_dropped_and_counted():
    width, height = 3, 2
    good = np.full((width, height, 3), 2.0, dtype=np.float32)
    bad_values = [np.nan, np.inf, -np.inf]
    samples = [good]
    for component in range(3):
        for bad in bad_values:
            sample = np.full((width, height, 3), 2.0, dtype=np.float32)
            sample[:, :, component] = bad
            samples.append(sample)
    samples.append(np.full((width, height, 3), 4.0, dtype=np.float32))
    film = Film(width, height)
    film.reset(width, height)
    add_from_array(film, np.stack(samples), width, height)

    np.testing.assert_array_equal(film.sample_counts(), 2)
    np.testing.assert_array_equal(film.rejected_counts(), 9)
    np.testing.assert_array_equal(film.mean_image(), 3.0)
    stats = film.stats()
    assert stats["rejected"] == 9 * width * height
    assert stats["min_spp"] == 2 and stats["mean_spp"] == pytest.approx(2.0)


def test_welford_variance_matches_numpy_unbiased_variance():
    rng = np.random.default_rng(7)
    width, height, count = 5, 3, 257
    samples = rng.lognormal(0.0, 1.0, size=(count, width, height, 3)).astype(np.float32)
    film = Film(8, 8)
    film.reset(width, height)
    add_from_array(film, samples, width, height)

    as_rows = samples.transpose(0, 2, 1, 3)[:, ::-1]  # [s, x, y] y-up -> [s, row, column]
    expected_mean = as_rows.astype(np.float64).mean(axis=0)
    expected_variance_of_mean = as_rows.astype(np.float64).var(axis=0, ddof=1) / count
    np.testing.assert_allclose(film.mean_image(), expected_mean, rtol=1e-5)
    np.testing.assert_allclose(film.variance_of_mean_image(), expected_variance_of_mean, rtol=1e-4)

    luminance = lambda rgb: rgb @ np.array([0.2126, 0.7152, 0.0722])
    relative = luminance(np.sqrt(expected_variance_of_mean)) / np.maximum(luminance(expected_mean), 1e-3)
    stats = film.stats()
    assert stats["noise"] == pytest.approx(math.sqrt(np.mean(relative**2)), rel=1e-4)
    assert stats["min_spp"] == count and stats["rejected"] == 0


def test_reset_clears_everything():
    film = Film(4, 4)
    film.reset(4, 4)
    add_constant(film, ti.math.vec3(1.0, 2.0, 3.0), 10, 4, 4)
    add_from_array(film, np.full((1, 4, 4, 3), np.nan, dtype=np.float32), 4, 4)
    film.reset(4, 4)
    np.testing.assert_array_equal(film.mean_image(), 0.0)
    np.testing.assert_array_equal(film.sample_counts(), 0)
    np.testing.assert_array_equal(film.rejected_counts(), 0)
    assert (film.m2.to_numpy() == 0).all()
    stats = film.stats()
    assert stats["min_spp"] == 0 and stats["rejected"] == 0 and stats["noise"] == math.inf


def test_active_region_smaller_than_max():
    film = Film(8, 6)
    film.reset(3, 2)
    assert (film.width, film.height) == (3, 2)
    samples = np.zeros((2, 3, 2, 3), dtype=np.float32)
    samples[:, 0, 1] = [[1.0, 1.0, 1.0], [3.0, 3.0, 3.0]]  # pixel x=0, y=1: top-left in row-0-top
    add_from_array(film, samples, 3, 2)
    mean = film.mean_image()
    assert mean.shape == (2, 3, 3) and film.sample_counts().shape == (2, 3)
    np.testing.assert_array_equal(mean[0, 0], 2.0)
    assert mean.sum() == pytest.approx(6.0)
    stats = film.stats()
    assert stats["min_spp"] == 2 and stats["mean_spp"] == pytest.approx(2.0)
    # Nothing outside the active region was touched.
    assert film.count.to_numpy()[3:, :].sum() == 0 and film.count.to_numpy()[:, 2:].sum() == 0


def test_reset_rejects_sizes_above_max():
    film = Film(4, 4)
    with pytest.raises(ValueError):
        film.reset(5, 4)
    with pytest.raises(ValueError):
        film.reset(4, 0)


def test_allocations_round_up_to_whole_steps():
    from renderer.runtime.allocation import ALLOCATION_STEP, allocation_size

    assert ALLOCATION_STEP == 64
    assert allocation_size(1, 1) == (64, 64)
    assert allocation_size(64, 65) == (64, 128)
    assert allocation_size(1920, 1080) == (1920, 1088)
    with pytest.raises(ValueError, match="positive"):
        allocation_size(0, 10)


def test_a_render_is_the_same_in_any_allocation(tmp_path):
    """Renderers of nearby sizes share an allocation (and so their compiled programs); one of
    another allocation, reset to the same active size, renders the same pixels bit for bit."""
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from tests.scene_builder import furnace_toml, scene_from_toml

    scene = scene_from_toml(tmp_path, furnace_toml(ball_kind="dielectric", floor=True))
    small, large = Renderer(scene, (20, 10)), Renderer(scene, (70, 40))
    assert small.film.mean.shape == (64, 64) and large.film.mean.shape == (128, 64)
    assert (small.film.width, small.film.height) == (20, 10)
    large.reset(20, 10)
    images = []
    for r in (small, large):
        r.render(CameraFrame.from_spec(scene.camera), 3, integrator="mis", seed=4)
        images.append((r.image(), r.film.variance_of_mean_image(), r.film.stats()))
    assert images[0][0].shape == (10, 20, 3) and images[0][0].mean() > 0.01
    np.testing.assert_array_equal(images[0][0], images[1][0])
    np.testing.assert_array_equal(images[0][1], images[1][1])

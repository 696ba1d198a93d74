"""End-to-end renders at tiny sizes: reproducibility, Mitsuba's depth convention, furnace tests.

Statistical checks are z-tests on the image mean at a stated significance level: pixels are
independent (each has its own random key), so the variance of the mean of N pixel means is the
sum of their variances-of-the-mean over N^2.
"""
import numpy as np
import pytest
from scipy import stats

from renderer.camera import CameraFrame
from renderer.film.pixel_slices import BANDS, INTERLEAVED, ROUND_SLICES, slice_mask
from renderer.renderer import Renderer
from tests.scene_builder import furnace_toml, scene_from_toml

ALPHA = 0.01  # two-sided significance level of every z-test here


def render(scene, spp, integrator="path", **kw):
    """These tests check the path tracer's exact behaviour (integrator agreement lives in
    test_integrator_agreement.py)."""
    kw["integrator"] = integrator
    r = Renderer(scene)
    r.render(CameraFrame.from_spec(scene.camera), spp, **kw)
    return r


def z_test_mean(renderer, expected):
    """z of the image mean of one channel (green): the three channels of a grey scene are the
    same numbers, so pooling them would count each sample three times."""
    mean = renderer.film.mean_image()[..., 1]
    var = renderer.film.variance_of_mean_image()[..., 1]
    n = mean.size
    z = (mean.mean() - expected) / np.sqrt(var.sum() / n**2)
    return z, stats.norm.ppf(1 - ALPHA / 2)


@pytest.fixture(scope="module")
def furnace_diffuse(tmp_path_factory):
    return scene_from_toml(tmp_path_factory.mktemp("furnace"), furnace_toml(floor=False))


def test_same_seed_same_image_and_split_passes_equal_one_pass(tmp_path):
    scene = scene_from_toml(tmp_path, furnace_toml(albedo=0.5))
    camera = CameraFrame.from_spec(scene.camera)
    r = Renderer(scene)
    r.render(camera, 8, integrator="path", seed=7)
    one = r.image().copy()
    r.reset()
    r.render(camera, 3, integrator="path", seed=7)
    r.render(camera, 5, integrator="path", seed=7)
    assert np.array_equal(one, r.image()), "counter-based sampling: 3+5 spp must equal 8 spp bit for bit"
    # Passes of 37 slices, rounds after the first cut into bands of rows (the viewer's still
    # frames): each pass samples its band's rows, and the film ends the same bit for bit.
    r.reset()
    r.bands_after_first_round = True
    width, height = r.film.width, r.film.height
    while r.slices_done < 8 * ROUND_SLICES:
        first, before = r.slices_done % ROUND_SLICES, r.film.sample_counts()
        order = r.round_order()
        assert order == (BANDS if r.slices_done >= ROUND_SLICES else INTERLEAVED)
        count = min(37, ROUND_SLICES - first)
        r.render_slices(camera, count, integrator="path", seed=7)
        changed = r.film.sample_counts() != before
        np.testing.assert_array_equal(changed, slice_mask(first, count, width, height, order)[::-1])
        if order == BANDS:  # the HUD's spp: exact for bands (interleaved: the share of slices)
            assert r.film.sample_counts().mean() == pytest.approx(r.mean_spp, rel=1e-9)
    assert np.array_equal(one, r.image())
    r.bands_after_first_round = False
    r.reset()
    r.render(camera, 8, integrator="path", seed=8)
    assert not np.array_equal(one, r.image())


def test_work_stats_reduce_the_active_region_of_the_work_field(furnace_diffuse):
    """The HUD's work per ray is reduced on the device row by row: it equals the sums of the
    downloaded field over the active region (a smaller one after a reset to a lower size)."""
    r = Renderer(furnace_diffuse)
    camera = CameraFrame.from_spec(furnace_diffuse.camera)
    for width, height in ((r.film.width, r.film.height), (r.film.width - 5, r.film.height - 3)):
        r.reset(width, height)
        r.render(camera, 3, integrator="path", seed=2)
        totals = r.work.to_numpy()[:width, :height].reshape(-1, 3).sum(axis=0, dtype=np.float64)
        stats = r.work_stats()
        assert totals[2] > 0
        assert stats["work_per_ray"] == pytest.approx(totals[0] / totals[2], rel=1e-6)
        assert stats["tests_per_ray"] == pytest.approx(totals[1] / totals[2], rel=1e-6)
        assert stats["rays_per_sample"] == pytest.approx(totals[2] / (3 * width * height), rel=1e-6)


def test_white_furnace_diffuse_is_exactly_the_environment(furnace_diffuse):
    """Albedo 1 under a constant sky: every path returns the sky radiance, 0.5, exactly."""
    r = render(furnace_diffuse, 16)
    np.testing.assert_allclose(r.image(), 0.5, rtol=1e-6)


def test_analytic_cavity_radiance(tmp_path):
    """Inside a diffuse cavity of albedo 0.5 emitting 0.5, the radiance is 0.5 / (1 - 0.5) = 1."""
    from tests.scene_builder import cavity_toml

    r = render(scene_from_toml(tmp_path, cavity_toml()), 64)
    assert r.film.stats()["rejected"] == 0
    z, critical = z_test_mean(r, 1.0)
    assert abs(z) < critical, f"mean {r.image().mean()} (z = {z:.2f})"


def test_max_depth_follows_mitsuba_convention(tmp_path):
    """Depth 1 sees emitters only (the diffuse floor is black); depth 2 adds direct light, which for
    a floor of albedo a under a constant sky L is exactly a * L on every floor pixel."""
    body = furnace_toml(env=0.5, albedo=0.6, max_depth=1).replace(
        'position = [0.0, 1.5, 3.0]', 'position = [0.0, 2.0, 0.01]').replace(
        'look_at = [0.0, 0.4, 0.0]', 'look_at = [0.0, 0.0, -0.5]').replace('fov = 50', 'fov = 20')
    body = body.replace('type = "sphere"', 'type = "sphere"\nscale = 0.01').replace(
        'translate = [0.0, 0.5, 0.0]', 'translate = [3.0, 0.5, 0.0]')
    scene = scene_from_toml(tmp_path, body)
    depth1 = render(scene, 4, max_depth=1).image()
    assert np.all(depth1 == 0.0)
    depth2 = render(scene, 4, max_depth=2).image()
    np.testing.assert_allclose(depth2, 0.6 * 0.5, rtol=1e-5)


def test_glass_sphere_furnace_conserves_radiance(tmp_path):
    """A clear smooth glass ball in a white furnace: Fresnel splits are chosen
    with their own probability and the 1/eta^2 radiance scaling cancels in and out, so the
    expectation is the sky radiance everywhere."""
    scene = scene_from_toml(tmp_path, furnace_toml(ball_kind="dielectric", floor=False))
    r = render(scene, 64)
    z, critical = z_test_mean(r, 0.5)
    assert abs(z) < critical, f"mean {r.image().mean()} (z = {z:.2f})"


def test_mirror_furnace_is_exact(tmp_path):
    """A perfect mirror ball (F0 = 1, so Schlick's F = 1) under a constant sky: every path returns 0.5."""
    scene = scene_from_toml(tmp_path, furnace_toml(ball_kind="conductor", floor=False))
    r = render(scene, 4)
    np.testing.assert_allclose(r.image(), 0.5, rtol=1e-6)



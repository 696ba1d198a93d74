"""Adaptive sampling (renderer/adaptive.py): the minimum spp, unbiasedness where pixels stopped,
exact continuation from a checkpointed state."""
import numpy as np
import pytest

from renderer.adaptive import STOPPED, is_check_point, next_check
from renderer.camera import CameraFrame
from renderer.renderer import AdaptiveSettings, Renderer
from renderer.scene import load_scene
from renderer.scene.catalog import resolve_scene
from tests.stats.image_tests import image_mean_z, pixel_z_test

ALPHA = 0.01  # the suite's level for image comparisons (tests/stats/image_tests.py)
SIZE = (32, 32)


def cornell():
    return load_scene(resolve_scene("cornell_box"))


def adaptive_renderer(scene, threshold, min_spp, spp, seed=5):
    renderer = Renderer(scene, SIZE)
    renderer.set_adaptive(AdaptiveSettings(threshold, min_spp))
    renderer.render(CameraFrame.from_spec(scene.camera), spp, "mis", seed=seed)
    return renderer


def test_check_points_double_from_the_minimum():
    assert [n for n in range(1, 130) if is_check_point(n, 8)] == [8, 16, 32, 64, 128]
    assert next_check(0, 8) == 8 and next_check(8, 8) == 16 and next_check(20, 8) == 32


def test_no_pixel_stops_before_the_minimum_spp():
    # A threshold every pixel meets at once: the rule still waits for min_spp, then for a second
    # check at twice that (a variance from 8 samples must be confirmed by 16).
    renderer = adaptive_renderer(cornell(), threshold=1e6, min_spp=8, spp=64)
    counts = renderer.film.sample_counts() + renderer.film.rejected_counts()
    assert counts.min() >= 8
    assert (counts == 16).all()
    assert renderer.pixels_active == 0
    assert (renderer.film.state().adaptive == STOPPED).all()


def test_an_unreachable_threshold_samples_uniformly():
    scene = cornell()
    renderer = adaptive_renderer(scene, threshold=1e-9, min_spp=4, spp=20)
    uniform = Renderer(scene, SIZE)
    uniform.render(CameraFrame.from_spec(scene.camera), 20, "mis", seed=5)
    assert np.array_equal(renderer.image(), uniform.image())
    assert (renderer.film.sample_counts() + renderer.film.rejected_counts() == 20).all()


def test_adaptive_render_is_unbiased_where_it_stopped():
    """Pixels adaptive sampling stopped, against a uniform render with another seed: the suite's
    per-pixel z-test (Sidak-corrected, 99.75% of pixel channels) and the z of the image mean over
    those pixels, at ALPHA."""
    scene = cornell()
    adaptive = adaptive_renderer(scene, threshold=0.15, min_spp=16, spp=256, seed=11)
    uniform = Renderer(scene, SIZE)
    uniform.render(CameraFrame.from_spec(scene.camera), 256, "mis", seed=12)
    counts = adaptive.film.sample_counts() + adaptive.film.rejected_counts()
    # Stopped before the maximum (a pixel the check at 256 spp stops took every sample anyway).
    stopped = (adaptive.film.state().adaptive == STOPPED) & (counts < 256)
    assert 0.1 < stopped.mean() < 0.95, f"{stopped.mean():.2f} of the pixels stopped: the test needs both kinds"
    a = (adaptive.image()[stopped][None], adaptive.film.variance_of_mean_image()[stopped][None])
    b = (uniform.image()[stopped][None], uniform.film.variance_of_mean_image()[stopped][None])
    passed, fraction, *_ = pixel_z_test(*a, *b, alpha=ALPHA)
    assert passed, f"{fraction:.4f} of stopped pixel channels agree"
    for channel in range(3):
        z = image_mean_z(a, b, channel)
        assert abs(z) < 2.576, f"channel {channel}: image mean z = {z:.2f} over {stopped.sum()} stopped pixels"


def test_a_continued_adaptive_render_is_bit_identical():
    scene = cornell()
    straight = adaptive_renderer(scene, threshold=0.1, min_spp=4, spp=40)
    first = adaptive_renderer(scene, threshold=0.1, min_spp=4, spp=11)
    state, slices = first.state(), first.slices_done
    second = Renderer(scene, SIZE)
    second.set_adaptive(AdaptiveSettings(0.1, 4))
    second.restore(state, slices)
    second.render(CameraFrame.from_spec(scene.camera), 40 - 11, "mis", seed=5)
    assert np.array_equal(second.film.state().adaptive, straight.film.state().adaptive)
    assert np.array_equal(second.image(), straight.image())
    assert second.pixels_active == straight.pixels_active


def test_invalid_settings_are_refused():
    renderer = Renderer(cornell(), (8, 8))
    with pytest.raises(ValueError, match="threshold"):
        renderer.set_adaptive(AdaptiveSettings(0.0))

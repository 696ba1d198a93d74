"""Adaptive sampling (renderer/film/adaptive.py): the minimum spp, unbiasedness where pixels stopped,
exact continuation from a checkpointed state.

The renders share one Renderer (each starts from reset(): film, adaptive state and rounds
cleared), so the module compiles its kernels once; the continued render alone gets a new one, as
a resumed render would."""
import numpy as np
import pytest

from renderer.film.adaptive import STOPPED, is_check_point, next_check
from renderer.camera import CameraFrame
from renderer.renderer import AdaptiveSettings, Renderer
from renderer.scene import load_scene
from renderer.scene.catalog import resolve_scene
from tests.stats.image_tests import image_mean_z, pixel_z_test

ALPHA = 0.01  # the suite's level for image comparisons (tests/stats/image_tests.py)
SIZE = (32, 32)


@pytest.fixture(scope="module")
def cornell():
    return load_scene(resolve_scene("cornell_box"))


@pytest.fixture(scope="module")
def renderer(cornell):
    return Renderer(cornell, SIZE)


def rendered(renderer, spp, seed, adaptive=None):
    """`renderer` from an empty film: `spp` samples of `mis`, adaptive (AdaptiveSettings) or not."""
    renderer.reset()
    renderer.set_adaptive(adaptive)
    renderer.render(CameraFrame.from_spec(renderer.scene.camera), spp, "mis", seed=seed)
    return renderer


def test_check_points_double_from_the_minimum():
    assert [n for n in range(1, 130) if is_check_point(n, 8)] == [8, 16, 32, 64, 128]
    assert next_check(0, 8) == 8 and next_check(8, 8) == 16 and next_check(20, 8) == 32


def test_no_pixel_stops_before_the_minimum_spp(renderer):
    # A threshold every pixel meets at once: the rule still waits for min_spp, then for a second
    # check at twice that (a variance from 8 samples must be confirmed by 16).
    rendered(renderer, 64, 5, AdaptiveSettings(1e6, 8))
    counts = renderer.film.sample_counts() + renderer.film.rejected_counts()
    assert counts.min() >= 8
    assert (counts == 16).all()
    assert renderer.pixels_active == 0
    assert (renderer.film.state().adaptive == STOPPED).all()


def test_an_unreachable_threshold_samples_uniformly(renderer):
    rendered(renderer, 20, 5, AdaptiveSettings(1e-9, 4))
    adaptive = renderer.image()
    assert (renderer.film.sample_counts() + renderer.film.rejected_counts() == 20).all()
    uniform = rendered(renderer, 20, 5).image()
    assert np.array_equal(adaptive, uniform)


def test_adaptive_render_is_unbiased_where_it_stopped(renderer):
    """Pixels adaptive sampling stopped, against a uniform render with another seed: the suite's
    per-pixel z-test (Sidak-corrected, 99.75% of pixel channels) and the z of the image mean over
    those pixels, at ALPHA."""
    rendered(renderer, 256, 11, AdaptiveSettings(0.08, 16))
    counts = renderer.film.sample_counts() + renderer.film.rejected_counts()
    # Stopped before the maximum (a pixel the check at 256 spp stops took every sample anyway).
    stopped = (renderer.film.state().adaptive == STOPPED) & (counts < 256)
    assert 0.1 < stopped.mean() < 0.95, f"{stopped.mean():.2f} of the pixels stopped: the test needs both kinds"
    a = (renderer.image()[stopped][None], renderer.film.variance_of_mean_image()[stopped][None])
    rendered(renderer, 256, 12)
    b = (renderer.image()[stopped][None], renderer.film.variance_of_mean_image()[stopped][None])
    passed, fraction, *_ = pixel_z_test(*a, *b, alpha=ALPHA)
    assert passed, f"{fraction:.4f} of stopped pixel channels agree"
    for channel in range(3):
        z = image_mean_z(a, b, channel)
        assert abs(z) < 2.576, f"channel {channel}: image mean z = {z:.2f} over {stopped.sum()} stopped pixels"


def test_a_continued_adaptive_render_is_bit_identical(cornell, renderer):
    settings = AdaptiveSettings(0.1, 4)
    straight = rendered(renderer, 40, 5, settings)
    expected = (straight.film.state().adaptive, straight.image(), straight.pixels_active)
    first = rendered(renderer, 11, 5, settings)
    state, slices = first.state(), first.slices_done
    second = Renderer(cornell, SIZE)
    second.set_adaptive(settings)
    second.restore(state, slices)
    second.render(CameraFrame.from_spec(cornell.camera), 40 - 11, "mis", seed=5)
    assert np.array_equal(second.film.state().adaptive, expected[0])
    assert np.array_equal(second.image(), expected[1])
    assert second.pixels_active == expected[2]


def test_invalid_settings_are_refused(renderer):
    with pytest.raises(ValueError, match="threshold"):
        renderer.set_adaptive(AdaptiveSettings(0.0))

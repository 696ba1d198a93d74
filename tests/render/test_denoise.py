"""Denoising (renderer/denoise.py, Intel Open Image Denoise): it keeps the image's light, leaves a
converged image alone, never sees a non-finite value, and the CLI writes its images and AOVs."""
import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.denoise import DenoiseInput, Denoiser, unavailable_reason
from renderer.renderer import Renderer
from renderer.scene import load_scene
from renderer.scene.catalog import resolve_scene

pytestmark = pytest.mark.skipif(unavailable_reason() is not None, reason="pyoidn is not installed here")


# The largest image of the module: one Renderer of this size renders every smaller one (its film's
# active region), so the module compiles its kernel once. Same seed and spp, same image as a
# Renderer of the smaller size: a pixel's samples depend on its index and sample count only.
FILM = (128, 128)


@pytest.fixture(scope="module")
def renderers():
    """Renderer with AOVs per scene name, made on first use, kept for the module."""
    return {}


def rendered(renderers, name, size, spp, seed):
    if name not in renderers:
        renderers[name] = Renderer(load_scene(resolve_scene(name)), FILM, aovs=True)
    renderer = renderers[name]
    renderer.reset(*size)
    renderer.render(CameraFrame.from_spec(renderer.scene.camera), spp, "mis", seed=seed)
    albedo, normal = renderer.aov_images()
    return renderer.image(), albedo, normal


def relative_mse(image, reference):
    return float(np.mean((image - reference) ** 2 / (reference**2 + 1e-2)))


@pytest.mark.parametrize("name, size", [("cornell_box", (128, 128))])  # (bench denoise covers five scenes)
def test_denoised_mean_stays_within_two_percent_of_the_raw_mean(renderers, name, size):
    raw, albedo, normal = rendered(renderers, name, size, 8, seed=1)
    denoised = Denoiser().denoise(DenoiseInput(raw, albedo, normal))
    assert np.isfinite(denoised).all() and denoised.shape == raw.shape
    for channel in range(3):
        ratio = denoised[..., channel].mean() / raw[..., channel].mean()
        assert abs(ratio - 1.0) < 0.02, f"channel {channel}: denoised / raw mean = {ratio:.4f}"
    # ... and it removes noise: closer to a converged render than the raw image is.
    reference, _, _ = rendered(renderers, name, size, 128, seed=2)
    assert relative_mse(denoised, reference) < 0.5 * relative_mse(raw, reference)


def test_denoising_a_converged_image_changes_it_no_more_than_its_noise(renderers):
    """At 512 spp the Cornell box still has some noise: an ideal denoiser would move the image by
    about its variance, relMSE(raw_a, raw_b) / 2 for two independent renders. Allowed: 1.25 times
    that, and the image mean within 1%."""
    raw, albedo, normal = rendered(renderers, "cornell_box", (64, 64), 512, seed=1)
    other, _, _ = rendered(renderers, "cornell_box", (64, 64), 512, seed=2)
    denoised = Denoiser().denoise(DenoiseInput(raw, albedo, normal))
    noise = relative_mse(other, raw) / 2
    assert relative_mse(denoised, raw) < 1.25 * noise
    assert abs(denoised.mean() / raw.mean() - 1.0) < 0.01


def test_no_non_finite_value_reaches_the_denoiser(monkeypatch):
    import pyoidn

    seen = {}

    def recording(color, albedo=None, normal=None, **options):
        seen.update(color=color, albedo=albedo, normal=normal)
        return color.copy()

    monkeypatch.setattr(pyoidn, "denoise", recording)
    colour = np.ones((8, 8, 3), np.float32)
    colour[0, 0] = [np.nan, np.inf, -np.inf]
    albedo = np.full((8, 8, 3), 0.5, np.float32)
    albedo[1, 1] = [np.nan, 2.0, -1.0]
    normal = np.zeros((8, 8, 3), np.float32)
    normal[2, 2] = [np.inf, 5.0, np.nan]
    out = Denoiser().denoise(DenoiseInput(colour, albedo, normal))
    for name, image in seen.items():
        assert np.isfinite(image).all(), name
    assert seen["albedo"].min() >= 0 and seen["albedo"].max() <= 1
    assert seen["normal"].min() >= -1 and seen["normal"].max() <= 1
    assert np.isfinite(out).all() and out.min() >= 0


def test_a_missing_library_is_one_line(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "pyoidn", None)  # import fails as if not installed
    reason = unavailable_reason()
    assert reason and "\n" not in reason and "pyoidn" in reason
    with pytest.raises(RuntimeError, match="pyoidn"):
        Denoiser()

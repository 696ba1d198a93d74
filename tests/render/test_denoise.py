"""Denoising (renderer/output/denoise.py, Intel Open Image Denoise): it keeps the image's light, leaves a
converged image alone, never sees a non-finite value, and the CLI writes its images and AOVs."""
from dataclasses import replace

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.output.denoise import DenoiseInput, Denoiser, unavailable_reason
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


def rendered(renderers, name, size, spp, seed, texture_filter=None):
    key = (name, texture_filter)
    if key not in renderers:
        scene = load_scene(resolve_scene(name))
        if texture_filter is not None:
            scene = replace(scene, render=replace(scene.render, texture_filter=texture_filter))
        renderers[key] = Renderer(scene, FILM, aovs=True)
    renderer = renderers[key]
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


@pytest.mark.parametrize("prefilter_aux", [False, True])
def test_denoising_a_converged_image_changes_it_no_more_than_its_noise(renderers, prefilter_aux):
    """At 256 spp the Cornell box still has some noise: an ideal denoiser would move the image by
    about its variance, relMSE(raw_a, raw_b) / 2 for two independent renders. Allowed: 1.25 times
    that, and the image mean within 1%. (At 128x128: on a 64x64 image the prefiltered AOVs'
    filter moved it 1.29 times its noise and the mean by 1.7%, from 0.75 and 0.5% without; at
    160x90 against a 8,192 spp reference it was the closer of the two at 128 and 512 spp.)"""
    raw, albedo, normal = rendered(renderers, "cornell_box", (128, 128), 256, seed=1)
    other, _, _ = rendered(renderers, "cornell_box", (128, 128), 256, seed=2)
    denoised = Denoiser(prefilter_aux=prefilter_aux).denoise(DenoiseInput(raw, albedo, normal))
    noise = relative_mse(other, raw) / 2
    assert relative_mse(denoised, raw) < 1.25 * noise
    assert abs(denoised.mean() / raw.mean() - 1.0) < 0.01


@pytest.mark.parametrize("prefilter_aux", [False, True])
def test_no_non_finite_value_reaches_the_denoiser(monkeypatch, prefilter_aux):
    from renderer.output.denoise import OidnFilters

    seen = []

    def recording(self, role, images, quality, **flags):
        seen.extend((role, name, image) for name, image in images.items())
        return np.full_like(next(iter(images.values())), np.nan) if role == "albedo" else images[next(iter(images))]

    monkeypatch.setattr(OidnFilters, "run", recording)
    colour = np.ones((8, 8, 3), np.float32)
    colour[0, 0] = [np.nan, np.inf, -np.inf]
    albedo = np.full((8, 8, 3), 0.5, np.float32)
    albedo[1, 1] = [np.nan, 2.0, -1.0]
    normal = np.zeros((8, 8, 3), np.float32)
    normal[2, 2] = [np.inf, 5.0, np.nan]
    out = Denoiser(prefilter_aux=prefilter_aux).denoise(DenoiseInput(colour, albedo, normal))
    roles = [role for role, _, _ in seen]
    assert roles == (["albedo", "normal"] if prefilter_aux else []) + ["color"] * 3
    for role, name, image in seen:
        # (the recording albedo prefilter returns NaN: what the colour filter gets is still finite)
        assert np.isfinite(image).all(), (role, name)
        if name == "albedo":
            assert image.min() >= 0 and image.max() <= 1
        if name == "normal":
            assert image.min() >= -1 and image.max() <= 1
    assert np.isfinite(out).all() and out.min() >= 0


def test_prefiltered_aovs_denoise_closer_to_the_reference_than_noisy_ones(renderers):
    """OIDN's recommended best quality (the AOVs denoised first, then `cleanAux`) against the noisy
    AOVs passed straight in, on a textured scene whose albedo AOV is noisy at 8 spp (its textures
    unfiltered: sub-pixel detail under anti-aliasing; mip-mapped, the albedo is smooth enough that
    the prefilter no longer pays, docs/findings.md "Texture filtering"): at least as close to a 256
    spp render of another seed."""
    raw, albedo, normal = rendered(renderers, "textured", (128, 72), 8, seed=1, texture_filter="none")
    reference, _, _ = rendered(renderers, "textured", (128, 72), 256, seed=2, texture_filter="none")
    denoiser = Denoiser()
    quick = denoiser.denoise(DenoiseInput(raw, albedo, normal), prefilter_aux=False)
    best = denoiser.denoise(DenoiseInput(raw, albedo, normal))
    assert np.isfinite(best).all() and best.shape == raw.shape
    assert relative_mse(best, reference) < relative_mse(quick, reference) < relative_mse(raw, reference)


def test_an_unknown_quality_is_one_line():
    with pytest.raises(ValueError, match="denoise quality must be one of high, balanced, fast"):
        Denoiser(quality="best")


def test_a_missing_library_is_one_line(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "pyoidn", None)  # import fails as if not installed
    reason = unavailable_reason()
    assert reason and "\n" not in reason and "pyoidn" in reason
    with pytest.raises(RuntimeError, match="pyoidn"):
        Denoiser()

"""Lantern's Cornell box against Mitsuba 3's, pixel by pixel, with Mitsuba's own render-test rule.

The reference (tests/data/cornell_mitsuba_mean.exr and cornell_mitsuba_var.exr, made by
scripts/mitsuba_reference.py) is `mi.cornell_box()` rendered by Mitsuba 3 at 64x64 with a box
filter: the per-pixel mean and the per-pixel variance of that mean. Lantern renders
assets/scenes/cornell_box.toml, the same scene value for value, at the same size; Mitsuba is not
needed to run these tests.

The rule, as in Mitsuba's src/render/tests/test_renders.py:
  - for every pixel and channel, z = (lantern_mean - ref_mean) / sqrt(lantern_var_of_mean +
    ref_var_of_mean) and its two-sided p-value 2 (1 - Phi(|z|));
  - significance alpha = 0.01, Sidak-corrected over the N pixels: a channel passes when
    p > 1 - (1 - alpha)^(1/N);
  - the image passes when (passing channels) / 3 >= 99.75 % of N.
Two deliberate differences from Mitsuba's version, which compares a test render against a
32k-spp reference: the variance is that of the difference of two estimates (both renders' noise,
Lantern's measured by its film, the reference's by the spread of its independent passes) instead
of the reference's per-sample variance over the test's spp, floored at 1e-4; and there is no floor:
a channel whose two variances are both 0 (pixels that see only the black outside of the box) must
be exactly equal instead.
`path` (BSDF sampling only) is compared over 2x2 pixel blocks, for the reason given at SETTINGS;
the integrators that sample the light are compared pixel by pixel. A last test compares the mean
of the whole image, which catches a small bias spread evenly over the image.

What the rule catches, measured on these settings: `mis` with its image scaled by 1.01 fails the
per-pixel rule, just (and the image mean, by z ~ 6-9); so do a mirrored image and a field of view
off by 0.3 degrees (39.0 or 39.6 instead of 39.3077). `path` fails at a scale of 1.01 (per pixel
and on the image mean) and with either wrong field of view.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from renderer.integrators import INTEGRATORS
from tests.stats.image_tests import PASS_FRACTION, pixel_z_test

ROOT = Path(__file__).resolve().parents[2]
SCENE_FILE = ROOT / "assets" / "scenes" / "cornell_box.toml"
REF_MEAN = ROOT / "tests" / "data" / "cornell_mitsuba_mean.exr"
REF_VAR = ROOT / "tests" / "data" / "cornell_mitsuba_var.exr"

ALPHA = 0.01  # significance level of the whole image, before the Sidak correction
SEED = 1
# integrator -> (samples per pixel, block size of the comparison). Lantern always renders at the
# reference's size; with a block size b > 1 both images are averaged over b x b blocks first (with a
# box filter that is exactly the same scene rendered at 1/b the size; the variance of a block mean is
# the sum of its pixels' variances / b^4, pixels being independent).
# `path` samples BSDFs only, so the faces lit only indirectly (the front of the short box) are
# reached by rare light-carrying paths: at 64x64 and 1,024 spp, 35 pixels there had no such path at
# all (mean and variance exactly 0 while Mitsuba's are not) and only 96.7 % of the pixels passed;
# at 16,384 spp 99.97 % passed, but that took 96 s. A z-test needs a near-normal pixel mean, i.e.
# many rare events per pixel: 4,096 spp over 2x2 blocks (16,384 samples per block; 8-17 s on a
# 2-core machine) gives that. Mitsuba's own path tracer, which samples the light as well, passes
# the per-pixel rule against this reference at 64x64 and 1,024 spp; so do `nee` and `mis`.
SETTINGS = {"path": (4096, 2), "nee": (1024, 1), "mis": (1024, 1)}
# Integrators that estimate the same radiance as Mitsuba's `path` (the debug views do not).
UNBIASED = [name for name in SETTINGS if name in INTEGRATORS]


def block_average(mean, var_of_mean, block):
    """Means and variances of the means over block x block pixel blocks (float64)."""
    mean, var = np.asarray(mean, np.float64), np.asarray(var_of_mean, np.float64)
    if block == 1:
        return mean, var
    h, w, c = mean.shape
    shape = (h // block, block, w // block, block, c)
    return mean.reshape(shape).mean(axis=(1, 3)), var.reshape(shape).sum(axis=(1, 3)) / block**4


def mitsuba_z_test(mean, var_of_mean, ref_mean, ref_var_of_mean, alpha=ALPHA):
    """(passed, fraction of pixels passing, per-channel pass mask, p-values, Sidak level)."""
    return pixel_z_test(mean, var_of_mean, ref_mean, ref_var_of_mean, alpha)


def describe_failure(mean, ref, success, p_value, blocks=4) -> str:
    """Where it fails: the worst pixels and, per image block, Lantern / Mitsuba and failures."""
    h, w, _ = mean.shape
    lines = ["worst pixels (row, col from the top left): lantern vs mitsuba RGB, p"]
    worst = np.argsort(p_value.min(axis=2), axis=None)[:8]
    for index in worst:
        r, c = divmod(int(index), w)
        lines.append(f"  ({r:2d}, {c:2d}) {np.round(mean[r, c], 4)} vs {np.round(ref[r, c], 4)}, "
                     f"p = {p_value[r, c].min():.1e}")
    lines.append(f"per {h // blocks}x{w // blocks} block: mean ratio lantern / mitsuba (RGB), failing channels")
    for br in range(blocks):
        cells = []
        for bc in range(blocks):
            rows = slice(br * h // blocks, (br + 1) * h // blocks)
            cols = slice(bc * w // blocks, (bc + 1) * w // blocks)
            lm, rm = mean[rows, cols].mean(axis=(0, 1)), ref[rows, cols].mean(axis=(0, 1))
            ratio = np.where(rm > 0, lm / np.where(rm > 0, rm, 1), np.nan)
            cells.append(f"{'/'.join(f'{v:.3f}' for v in ratio)} {np.count_nonzero(~success[rows, cols]):3d}")
        lines.append("  " + " | ".join(cells))
    return "\n".join(lines)


@pytest.fixture(scope="module")
def reference():
    if not (REF_MEAN.is_file() and REF_VAR.is_file()):
        pytest.skip(f"Mitsuba reference images missing ({REF_MEAN.name}, {REF_VAR.name} in tests/data); "
                    "make them with scripts/mitsuba_reference.py")
    from renderer.output.image_io import read_exr

    return read_exr(REF_MEAN), read_exr(REF_VAR)


@pytest.fixture(scope="module")
def scene():
    from renderer.scene import load_scene

    return load_scene(SCENE_FILE)


@pytest.fixture(scope="module")
def lantern(scene, reference):
    """render(integrator) -> (mean, variance of the mean) at the reference's size, rendered once."""
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    ref, _ = reference
    size = (ref.shape[1], ref.shape[0])
    done = {}

    def render(integrator):
        if integrator not in done:
            renderer = Renderer(scene, size)
            spp, _ = SETTINGS[integrator]
            camera = CameraFrame.from_spec(scene.camera)
            renderer.render(camera, spp, integrator=integrator, max_depth=8, seed=SEED)
            assert renderer.film.stats()["rejected"] == 0
            done[integrator] = renderer.film.mean_image(), renderer.film.variance_of_mean_image()
        return done[integrator]

    return render


def test_reference_images_are_sound(reference):
    ref, ref_var = reference
    assert ref.shape == ref_var.shape and ref.shape[2] == 3 and ref.shape[0] == ref.shape[1]
    assert np.all(np.isfinite(ref)) and np.all(np.isfinite(ref_var))
    assert ref.min() >= 0 and ref_var.min() >= 0
    # Orientation as Mitsuba renders it: the red wall (x = -1) on the left, the green one on the right.
    quarter = ref.shape[1] // 4
    left, right = ref[:, :quarter].mean(axis=(0, 1)), ref[:, -quarter:].mean(axis=(0, 1))
    assert left[0] > left[1] and right[1] > right[0]


@pytest.mark.parametrize("integrator", UNBIASED)
def test_cornell_box_matches_mitsuba(reference, lantern, integrator):
    spp, block = SETTINGS[integrator]
    ref, ref_var = block_average(*reference, block)
    mean, var = block_average(*lantern(integrator), block)
    passed, fraction, success, p_value, level = mitsuba_z_test(mean, var, ref, ref_var)
    assert passed, (f"{integrator} ({spp} spp, {block}x{block} blocks): {fraction:.2%} of {mean.shape[0]}x"
                    f"{mean.shape[1]} pixels pass the z-test at the Sidak level {level:.2e} "
                    f"(need {PASS_FRACTION:.2%})\n" + describe_failure(mean, ref, success, p_value))


@pytest.mark.parametrize("integrator", UNBIASED)
def test_cornell_box_image_mean_matches_mitsuba(reference, lantern, integrator):
    """The mean over all pixels: far more sensitive to a small bias spread over the whole image
    than the per-pixel rule (pixels are independent, so variances add). Two-sided z-test per
    channel at ALPHA, Sidak-corrected over the 3 channels."""
    ref, ref_var = reference
    mean, var = lantern(integrator)
    n = ref.shape[0] * ref.shape[1]
    difference = mean.astype(np.float64).mean(axis=(0, 1)) - ref.astype(np.float64).mean(axis=(0, 1))
    sigma = np.sqrt((var.astype(np.float64).sum(axis=(0, 1)) + ref_var.astype(np.float64).sum(axis=(0, 1))) / n**2)
    z = difference / sigma
    critical = stats.norm.isf(-np.expm1(np.log1p(-ALPHA) / 3) / 2)
    assert np.all(np.abs(z) < critical), (f"{integrator}: image mean differs from Mitsuba's by {difference} "
                                          f"(relative {difference / ref.mean(axis=(0, 1))}, z = {z}, "
                                          f"critical {critical:.2f})")


# --- glass under an environment map --------------------------------------------------------------
# tests/data/glass_reference.toml: an analytic glass sphere and a flat-shaded glass triangle ball
# (every ray leaving it is a back-face hit: the case a barycentric bug once moved) on a floor under
# venice.exr, and Mitsuba 3's rendering of the same scene value for value
# (renderer/bench/mitsuba_side.glass_scene_dict; scripts/mitsuba_reference.py --scene glass), 48x48,
# 65,536 spp. Light reaches the camera through delta refractions, so every integrator sees the
# environment through the glass the same way; `mis` and `path` at 1,024 spp are compared with the
# same per-pixel rule and image-mean test as the Cornell box.
GLASS_SCENE = ROOT / "tests" / "data" / "glass_reference.toml"
GLASS_MEAN = ROOT / "tests" / "data" / "glass_mitsuba_mean.exr"
GLASS_VAR = ROOT / "tests" / "data" / "glass_mitsuba_var.exr"
GLASS_SPP = 1024


@pytest.fixture(scope="module")
def glass():
    """(reference mean, reference variance, render(integrator) -> (mean, variance))."""
    from renderer.camera import CameraFrame
    from renderer.output.image_io import read_exr
    from renderer.renderer import Renderer
    from renderer.scene import load_scene

    ref, ref_var = read_exr(GLASS_MEAN), read_exr(GLASS_VAR)
    scene = load_scene(GLASS_SCENE)
    done = {}

    def render(integrator):
        if integrator not in done:
            renderer = Renderer(scene, (ref.shape[1], ref.shape[0]))
            renderer.render(CameraFrame.from_spec(scene.camera), GLASS_SPP, integrator=integrator, seed=SEED)
            assert renderer.film.stats()["rejected"] == 0
            done[integrator] = renderer.film.mean_image(), renderer.film.variance_of_mean_image()
        return done[integrator]

    return ref, ref_var, render


@pytest.mark.parametrize("integrator", ["mis", "path"])
def test_glass_matches_mitsuba(glass, integrator):
    ref, ref_var, render = glass
    mean, var = render(integrator)
    passed, fraction, success, p_value, level = mitsuba_z_test(mean, var, ref, ref_var)
    assert passed, (f"glass, {integrator}: {fraction:.2%} of the pixels pass at the Sidak level {level:.2e} "
                    f"(need {PASS_FRACTION:.2%})\n" + describe_failure(mean, ref, success, p_value))
    n = ref.shape[0] * ref.shape[1]
    difference = mean.astype(np.float64).mean(axis=(0, 1)) - ref.astype(np.float64).mean(axis=(0, 1))
    sigma = np.sqrt((var.astype(np.float64).sum(axis=(0, 1)) + ref_var.astype(np.float64).sum(axis=(0, 1))) / n**2)
    critical = stats.norm.isf(-np.expm1(np.log1p(-ALPHA) / 3) / 2)
    assert np.all(np.abs(difference / sigma) < critical), (
        f"glass, {integrator}: image mean differs from Mitsuba's by {difference} "
        f"(relative {difference / ref.mean(axis=(0, 1))}, z = {difference / sigma})")

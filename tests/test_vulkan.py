"""The kernels stay valid for GPU back-ends: a tiny render on Vulkan (software lavapipe here).

Runs in subprocesses, since a process holds one Taichi runtime and the suite's is on the CPU.

Images of light are held to the CPU's as scripts/gpu_check.py holds a back-end: independent seeds
(its SEEDS), each side's per-pixel mean and variance of the mean, and its `compare` (the suite's
z-test, tests/stats/image_tests.py: every pixel channel at the Sidak level for the image, 99.75 %
of them passing, and the image means), here at COMPARE_ALPHA, a Sidak share of 0.01 over the
module's comparisons. Both sides take the same spp: at 16 spp a render of these scenes against a
long one fails the per-pixel rule where a skewed pixel's few samples missed its bright paths (its
mean and its variance both low), while two renders of equal spp differ symmetrically; 30 pairs of
CPU renders of each scene with other seeds all passed. Each test also shows what the comparison
would see: the Vulkan image with a tenth of its light lost fails (foggy: three tenths).
"""
import functools
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from renderer.output.image_io import read_exr
from scripts.gpu_check import SEEDS, compare
from tests.stats.chi2 import sidak_alpha

ROOT = Path(__file__).resolve().parents[1]
COMPARED_SIZE = (32, 18)
COMPARED_SPP = 16
MEDIA_SCENES = ["foggy", "prism", "goblet"]
COMPARE_ALPHA = sidak_alpha(0.01, 1 + len(MEDIA_SCENES))


@functools.cache  # asked by every Vulkan test: one probe per test process
def vulkan_available() -> bool:
    probe = "from renderer.runtime.arch import init_taichi; init_taichi('vulkan')"  # raises without a Vulkan device
    try:
        return subprocess.run([sys.executable, "-c", probe], capture_output=True, timeout=120, cwd=ROOT).returncode == 0
    except subprocess.TimeoutExpired:
        return False


@functools.cache
def vulkan_device() -> str:
    """The name of the device Taichi's Vulkan back-end picks, from its debug log ("" if none):
    "llvmpipe (...)" is Mesa's software driver, lavapipe."""
    probe = "import taichi as ti; ti.init(arch=ti.vulkan, log_level=ti.TRACE, offline_cache=False)"
    try:
        proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return ""
    found = re.search(r'Vulkan Device "([^"]+)"', proc.stdout + proc.stderr)
    return found.group(1) if found else ""


def render(arch, integrator, out, spp, scene="showcase", size="32x18", options=()):
    cmd = [sys.executable, str(ROOT / "app.py"), "render", scene, "--size", size, "--spp", str(spp),
           "--integrator", integrator, "--arch", arch, "--out", str(out), *options]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return read_exr(out)


def vulkan_render_with_variance(tmp_path, scene, integrator):
    """(mean, variance of the mean) of a COMPARED_SPP render on Vulkan at COMPARED_SIZE, by the
    command line with the checked side's seed."""
    size = "x".join(map(str, COMPARED_SIZE))
    variance = tmp_path / f"{scene}_vk_variance.exr"
    mean = render("vulkan", integrator, tmp_path / f"{scene}_vk.exr", COMPARED_SPP, scene=scene, size=size,
                  options=("--seed", str(SEEDS["checked"]), "--variance", str(variance)))
    return mean, read_exr(variance)


def cpu_render_with_variance(scene, integrator):
    """The same on the CPU (this process's runtime) with the reference side's seed."""
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any, resolve_scene

    loaded = load_any(resolve_scene(scene))
    renderer = Renderer(loaded, COMPARED_SIZE)
    renderer.render(CameraFrame.from_spec(loaded.camera), COMPARED_SPP, integrator=integrator, seed=SEEDS["reference"])
    assert renderer.film.stats()["rejected"] == 0
    return renderer.film.mean_image(), renderer.film.variance_of_mean_image()


def assert_agrees_and_sees_a_loss(cpu, vulkan, loss, what):
    """Vulkan agrees with the CPU by compare(), and its image with `loss` of the light taken away
    would not (the variance of a scaled estimate scales by the square)."""
    agreement = compare(cpu, vulkan, COMPARE_ALPHA)
    assert agreement.passed, f"{what}: {agreement.text()}"
    keep = 1.0 - loss
    darker = compare(cpu, (vulkan[0] * keep, vulkan[1] * keep * keep), COMPARE_ALPHA)
    assert not darker.passed, f"{what} with {loss:.0%} of its light lost: {darker.text()}"


@pytest.mark.vulkan
def test_vulkan_render_matches_cpu(tmp_path):
    if not vulkan_available():
        pytest.skip("no Vulkan driver (install libvulkan1 mesa-vulkan-drivers)")
    # Normals are deterministic given the seed: the two back-ends must agree up to f32 rounding
    # differences in transcendental functions, which move a few silhouette pixels at most.
    cpu = render("cpu", "normals", tmp_path / "cpu.exr", 2)
    gpu = render("vulkan", "normals", tmp_path / "vk.exr", 2)
    close = np.all(np.abs(cpu - gpu) < 1e-3, axis=-1)
    assert close.mean() > 0.97, f"only {close.mean():.1%} of pixels agree"
    # The path tracer compiles and runs there too, and produces finite, non-blank radiance: the
    # CPU's, by the z-test.
    vulkan = vulkan_render_with_variance(tmp_path, "showcase", "path")
    path = vulkan[0]
    assert np.all(np.isfinite(path)) and path.mean() > 0.01
    assert_agrees_and_sees_a_loss(cpu_render_with_variance("showcase", "path"), vulkan, 0.1, "showcase, path")


@pytest.mark.vulkan
@pytest.mark.parametrize("scene", MEDIA_SCENES)
def test_vulkan_runs_media_and_dispersion(tmp_path, scene):
    """The tracer's optional parts (media, null surfaces, fog, spectral paths, Bezier patches) compile for Vulkan
    and give finite, non-blank radiance there: the CPU's, by the z-test. Foggy's light reaches
    the image in rare bright paths from its lamp through the haze: at this budget a tenth of it
    lost hides in their noise (seen in none of 20 pairs of CPU renders), three tenths do not
    (seen in all 20)."""
    if not vulkan_available():
        pytest.skip("no Vulkan driver (install libvulkan1 mesa-vulkan-drivers)")
    vulkan = vulkan_render_with_variance(tmp_path, scene, "mis")
    image = vulkan[0]
    assert np.all(np.isfinite(image)) and image.mean() > 1e-3
    assert_agrees_and_sees_a_loss(cpu_render_with_variance(scene, "mis"), vulkan, 0.3 if scene == "foggy" else 0.1,
                                  f"{scene}, mis")


@pytest.mark.vulkan
def test_vulkan_render_times_its_passes_after_they_finish(tmp_path):
    """GPU launches return before the work is done: the render command must wait for each pass,
    or its passes (sized by the measured rate) and its progress line go wild. Without the wait
    the last progress line read 95 Msamples/s for a 160x160 render that took 1.1 s for 16 spp
    (0.4 Msamples/s)."""
    if not vulkan_available():
        pytest.skip("no Vulkan driver (install libvulkan1 mesa-vulkan-drivers)")
    cmd = [sys.executable, str(ROOT / "app.py"), "render", "cornell_box", "--size", "64x64", "--spp", "16",
           "--integrator", "mis", "--arch", "vulkan", "--out", str(tmp_path / "cb.exr")]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    rates = [float(r) for r in re.findall(r"([\d.]+) Msamples/s", proc.stderr)]
    spp, seconds = map(float, re.findall(r"\(([\d.]+) spp in ([\d.]+) s\)", proc.stderr + proc.stdout)[-1])
    overall = 64 * 64 * spp / seconds / 1e6  # (the total includes the first, compiling pass)
    assert rates and max(rates) < 3.0 * overall, (rates, overall)


SAMPLE_COUNTS = """
from renderer.runtime.arch import init_taichi
init_taichi('vulkan')
from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any, resolve_scene
scene = load_any(resolve_scene('cornell_box'))
r = Renderer(scene, (80, 45))
camera = CameraFrame.from_spec(scene.camera)
r.render(camera, 4, integrator='normals', seed=1)
taken = r.film.sample_counts() + r.film.rejected_counts()
print('TAKEN', int(taken.min()), int(taken.max()))
for slices in (100, 29, 127):  # a round in partial interleaved passes (the viewer's first round)
    r.render_slices(camera, slices, integrator='normals', seed=1)
taken = r.film.sample_counts() + r.film.rejected_counts()
print('PASSES', int(taken.min()), int(taken.max()))
"""


@pytest.mark.vulkan
def test_vulkan_every_pixel_takes_every_sample_of_a_launch():
    """On lavapipe a launch of 4 samples a pixel gave the last, partial group of 128 pixels (80x45:
    16 of them) 3 each, and hard_cases / mis lost most of 256 (4-89 taken), biasing its image dark
    where paths are long. Vulkan renders now take one sample a launch
    (renderer.VULKAN_SAMPLES_PER_LAUNCH); only the counts tell, so the test reads them."""
    if not vulkan_available():
        pytest.skip("no Vulkan driver (install libvulkan1 mesa-vulkan-drivers)")
    proc = subprocess.run([sys.executable, "-c", SAMPLE_COUNTS], capture_output=True, text=True, timeout=600,
                          cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    taken = re.search(r"TAKEN (\d+) (\d+)", proc.stdout)
    assert taken and taken.groups() == ("4", "4"), proc.stdout
    passes = re.search(r"PASSES (\d+) (\d+)", proc.stdout)
    assert passes and passes.groups() == ("5", "5"), proc.stdout

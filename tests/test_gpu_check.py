"""scripts/gpu_check.py without a GPU: the skip path, and its comparison of two renders (the
suite's z-test) on CPU renders of a small scene: independent seeds agree, altered images do not."""
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any, resolve_scene
from scripts.gpu_check import SEEDS, _scene_result, compare, probe_arch, render_side

ROOT = Path(__file__).resolve().parents[1]
SIZE = (32, 32)
SPP = 64


def test_without_cuda_the_check_says_skipped_in_one_line():
    if probe_arch("cuda") == "cuda":
        pytest.skip("this machine has a CUDA device: the check would run in full")
    start = time.perf_counter()
    # The script's Python is $PYTHON (else .venv/bin/python, else python3): this interpreter, the
    # one that runs the suite and has the project's packages, whatever it is.
    proc = subprocess.run(["bash", str(ROOT / "scripts" / "gpu_check.sh")], capture_output=True, text=True,
                          timeout=60, cwd=ROOT, env={**os.environ, "PYTHON": sys.executable})
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "skipped: no CUDA device\n"
    assert time.perf_counter() - start < 30.0  # a probe, not a render


@pytest.fixture(scope="module")
def two_cpu_renders():
    """The Cornell box at 32x32, 64 spp, with the check's two seeds: (mean, variance) pairs."""
    scene = load_any(resolve_scene("cornell_box"))
    camera = CameraFrame.from_spec(scene.camera)
    renderer = Renderer(scene, SIZE)
    sides = []
    for side in ("reference", "checked"):
        renderer.reset()
        result = render_side(renderer, camera, SEEDS[side], min_spp=SPP, seconds=0.0)
        assert result.spp == SPP  # no time budget: exactly min_spp
        assert result.pixel_samples == (SPP, SPP)  # every pixel took every sample
        sides.append((result.mean, result.variance))
    assert not np.array_equal(sides[0][0], sides[1][0])  # independent noise
    return sides


def test_independent_cpu_renders_agree(two_cpu_renders):
    reference, checked = two_cpu_renders
    agreement = compare(reference, checked)
    assert agreement.passed, agreement.text()


def test_a_darker_image_is_found(two_cpu_renders):
    """A back-end that loses a tenth of the light everywhere: within the per-pixel noise at 64 spp,
    so the image means decide (z about 5 here, against a critical 2.58)."""
    reference, (mean, variance) = two_cpu_renders
    agreement = compare(reference, (mean * np.float32(0.9), variance))
    assert not agreement.passed, agreement.text()
    assert abs(agreement.mean_z) > agreement.critical_z


def test_a_wrong_tile_is_found(two_cpu_renders):
    """A back-end that gets a 4x4 tile of the lit back wall wrong (black): the per-pixel tests decide."""
    reference, (mean, variance) = two_cpu_renders
    altered = mean.copy()
    altered[8:12, 14:18] = 0.0
    agreement = compare(reference, (altered, variance))
    assert not agreement.passed, agreement.text()
    assert agreement.pixel_fraction < 1.0


def test_a_back_end_that_drops_samples_fails_whatever_its_images_say(tmp_path):
    """On lavapipe the last, partial group of 128 pixels stopped after 3 samples of a launch that
    asked for 4 or more; its image statistics could not tell (the pixels' means stay right). The
    check reads each pixel's sample count and fails such a back-end before comparing images."""
    jobs = {("s", side): {"start_s": 1.0} for side in ("reference", "checked")}
    rendered = {("s", "reference"): {"spp": 9, "render_s": 1.0, "pixel_samples": [9, 9]},
                ("s", "checked"): {"spp": 9, "render_s": 1.0, "pixel_samples": [4, 9]}}
    images = {job: tmp_path / "never_read.npz" for job in jobs}  # the verdict comes first
    result = _scene_result("s", jobs, rendered, images, 0.01)
    assert result["verdict"] == "FAIL (samples lost: checked: pixels took 4-9 of 9 samples)"

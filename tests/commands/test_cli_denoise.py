"""`render --denoise`, `--aovs` and `--noise-threshold` as a user runs them."""
import subprocess
import sys

import numpy as np
import pytest

from renderer.output.denoise import unavailable_reason
from renderer.output.image_io import read_exr_layers
from tests.commands.test_cli import ROOT, no_rendering, one_line_error, run_main  # noqa: F401 (a fixture)

needs_oidn = pytest.mark.skipif(unavailable_reason() is not None, reason="pyoidn is not installed here")


def render(*args):
    return subprocess.run([sys.executable, str(ROOT / "app.py"), "render", "cornell_box", "--size", "40x30",
                           "--arch", "cpu", *args], capture_output=True, text=True, timeout=300)


@needs_oidn
def test_denoise_aovs_and_adaptive_sampling_write_their_files(tmp_path):
    """One render to a PNG with everything on: the PNG is the denoised image, OUT.aovs.exr beside it
    holds the raw colour and the layers; the spp layer shows adaptive sampling at work."""
    out = tmp_path / "box.png"
    proc = render("--spp", "64", "--out", str(out), "--denoise", "--aovs", "--noise-threshold", "0.05",
                  "--min-spp", "8")
    assert proc.returncode == 0, proc.stderr
    assert out.stat().st_size > 0
    assert "denoised in" in proc.stdout and "adaptive:" in proc.stdout
    layers = read_exr_layers(tmp_path / "box.aovs.exr")
    assert {"RGB", "albedo", "normal", "variance", "spp", "stopped"} <= set(layers)
    spp, stopped = layers["spp"], layers["stopped"]
    assert spp.min() >= 8 and spp.max() == 64
    assert stopped.any() and (spp[stopped > 0] < 64).any()
    assert np.isfinite(layers["RGB"]).all() and layers["albedo"].max() <= 1.0


@needs_oidn
def test_an_exr_holds_the_denoised_image_and_its_layers(tmp_path):
    out = tmp_path / "box.exr"
    proc = render("--spp", "4", "--out", str(out), "--denoise", "--aovs")
    assert proc.returncode == 0, proc.stderr
    layers = read_exr_layers(out)
    assert {"RGB", "raw", "albedo", "normal", "variance", "spp"} <= set(layers)
    assert not np.array_equal(layers["RGB"], layers["raw"])  # the main image is the denoised one
    assert not (tmp_path / "box.aovs.exr").exists()


@pytest.mark.parametrize("argv, expected", [
    (["--integrator", "albedo", "--denoise"], "not an image of light"),
    (["--integrator", "sppm", "--noise-threshold", "0.1"], "whole-image iterations"),
    (["--noise-threshold", "0"], "must be a positive relative error"),
    (["--noise-threshold", "-1"], "must be a positive relative error"),
])
def test_impossible_combinations_are_one_line_errors(tmp_path, capsys, no_rendering, argv, expected):
    code, _, err = run_main(["render", "cornell_box", "--out", str(tmp_path / "a.png"), *argv], capsys)
    assert code != 0 and expected in one_line_error(err)


def test_a_missing_denoiser_is_one_line_before_rendering(tmp_path, capsys, no_rendering, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyoidn", None)
    code, _, err = run_main(["render", "cornell_box", "--out", str(tmp_path / "a.png"), "--denoise"], capsys)
    assert code != 0 and "pyoidn" in one_line_error(err)

"""`render --denoise`, `--aovs` and `--noise-threshold` as a user runs them."""
import subprocess
import sys

import numpy as np
import pytest

from renderer.output.denoise import unavailable_reason
from renderer.output.image_io import read_exr_layers
from tests.commands.test_cli import ROOT, no_rendering, one_line_error, run_main  # noqa: F401 (a fixture)

needs_oidn = pytest.mark.skipif(unavailable_reason() is not None, reason="pyoidn is not installed here")


SIZE = (40, 30)


def render(*args):
    return subprocess.run([sys.executable, str(ROOT / "app.py"), "render", "cornell_box", "--size",
                           f"{SIZE[0]}x{SIZE[1]}", "--arch", "cpu", *args], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def reference():
    """The Cornell box at the commands' size, 1024 spp of another seed (the commands render seed
    0): what a denoised image must come closer to than the raw one (as in tests/render/test_denoise.py)."""
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any, resolve_scene

    scene = load_any(resolve_scene("cornell_box"))
    renderer = Renderer(scene, SIZE)
    renderer.render(CameraFrame.from_spec(scene.camera), 1024, scene.render.integrator, seed=7)
    return renderer.image().astype(np.float64)


def display_mse(image, reference):
    """Mean squared error of an image shown as its PNG is (8-bit values of the default tone mapping;
    a uint8 image is a PNG's already) against the reference shown the same way. On the screen, not
    in linear relative error: at 40x30 that is decided by a few dark pixels beside the light's edges
    (the 4 spp EXR below: 0.050 denoised against 0.064 raw, while its median pixel is 5.7 times
    closer)."""
    from renderer.output.tonemap import tonemap_array

    shown = image if image.dtype == np.uint8 else tonemap_array(image, 0.0, "aces")
    return float(np.mean((shown.astype(np.float64) - tonemap_array(reference, 0.0, "aces")) ** 2))


@needs_oidn
def test_denoise_aovs_and_adaptive_sampling_write_their_files(tmp_path, reference):
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
    # The PNG shows the denoised image: closer to a long render than the raw colour beside it (the
    # aovs file's RGB), both as the PNG shows them. At 64 spp the raw image is already fair: the
    # denoiser takes 42 % of its error off (0.58 of it left; the raw image in the PNG: all of it).
    import imageio.v3 as iio

    png = iio.imread(out)
    assert png.shape == (SIZE[1], SIZE[0], 3) and png.dtype == np.uint8
    denoised_error, raw_error = display_mse(png, reference), display_mse(layers["RGB"], reference)
    assert denoised_error < 0.75 * raw_error, (denoised_error, raw_error)


@needs_oidn
def test_an_exr_holds_the_denoised_image_and_its_layers(tmp_path, reference):
    out = tmp_path / "box.exr"
    proc = render("--spp", "4", "--out", str(out), "--denoise", "--aovs")
    assert proc.returncode == 0, proc.stderr
    layers = read_exr_layers(out)
    assert {"RGB", "raw", "albedo", "normal", "variance", "spp"} <= set(layers)
    assert not np.array_equal(layers["RGB"], layers["raw"])  # the main image is the denoised one
    # ... less than half as far from a long render as the raw colour (0.41 of its error at 4 spp)
    denoised_error, raw_error = display_mse(layers["RGB"], reference), display_mse(layers["raw"], reference)
    assert denoised_error < 0.5 * raw_error, (denoised_error, raw_error)
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

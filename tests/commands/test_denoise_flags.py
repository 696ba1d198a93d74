"""`render --denoise` keeps the raw render beside the denoised image; `--no-denoise` (the default)
writes the raw render only, and on --resume overrides the checkpoint's choice."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import app
from renderer.output.checkpoint import save_checkpoint
from renderer.output.denoise import unavailable_reason
from renderer.output.image_io import read_exr
from tests.output.checkpoint_helpers import film_state, header_for

ROOT = Path(__file__).resolve().parents[2]
needs_oidn = pytest.mark.skipif(unavailable_reason() is not None, reason="pyoidn is not installed here")


def render(out: Path, *args) -> subprocess.CompletedProcess:
    proc = subprocess.run([sys.executable, str(ROOT / "app.py"), "render", "cornell_box", "--size", "40x30",
                           "--spp", "4", "--seed", "3", "--arch", "cpu", "--out", str(out), *args],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return proc


@needs_oidn
def test_the_raw_render_is_kept_beside_the_denoised_image(tmp_path):
    """The same seed rendered without denoising is the raw file, bit for bit (EXR) and pixel for
    pixel (PNG, tone-mapped alike); the denoised image is another. (Both renders keep the AOVs:
    the kernel that also traces them may round the colour's last bit differently.)"""
    plain = tmp_path / "plain"
    denoised = tmp_path / "denoised"
    for folder in (plain, denoised):
        folder.mkdir()
        for name in ("a.exr", "a.png"):
            proc = render(folder / name, "--aovs", *(["--denoise"] if folder is denoised else []))
            raw = folder / name.replace(".", ".raw.")
            if folder is denoised:
                assert f"{raw}  (the raw render, before denoising)" in proc.stdout.splitlines()
    # --no-denoise is the default
    assert sorted(p.name for p in plain.iterdir()) == ["a.aovs.exr", "a.exr", "a.png"]
    assert sorted(p.name for p in denoised.iterdir()) == ["a.aovs.exr", "a.exr", "a.png", "a.raw.exr", "a.raw.png"]
    np.testing.assert_array_equal(read_exr(denoised / "a.raw.exr"), read_exr(plain / "a.exr"))
    assert not np.array_equal(read_exr(denoised / "a.exr"), read_exr(plain / "a.exr"))
    with Image.open(denoised / "a.raw.png") as raw, Image.open(plain / "a.png") as expected:
        np.testing.assert_array_equal(np.asarray(raw), np.asarray(expected))
        assert "denoised" not in raw.text and raw.text["spp"] == "4"
    with Image.open(denoised / "a.png") as image:
        assert image.text["denoised"] == "Intel Open Image Denoise"


@pytest.mark.parametrize("flag, expected", [([], True), (["--no-denoise"], False), (["--denoise"], True)])
def test_a_resumed_render_keeps_the_checkpoints_denoising_unless_told(tmp_path, monkeypatch, flag, expected):
    from renderer.commands.render import plan_render

    monkeypatch.setattr("renderer.commands.render_job.check_denoising", lambda job: None)  # (pyoidn or not)
    scene = ROOT / "assets" / "scenes" / "cornell_box.toml"
    checkpoint = tmp_path / "a.ckpt"
    save_checkpoint(checkpoint, header_for(scene, denoise=True, out=str(tmp_path / "a.png")), film_state(24, 16, 1.0))
    plan = plan_render(app.build_parser().parse_args(["render", "--resume", str(checkpoint), *flag]))
    assert plan.job.denoise is expected


def test_no_denoise_is_the_default_of_render(tmp_path):
    from renderer.commands.render import plan_render

    plan = plan_render(app.build_parser().parse_args(["render", "cornell_box", "--out", str(tmp_path / "a.png")]))
    assert plan.job.denoise is False

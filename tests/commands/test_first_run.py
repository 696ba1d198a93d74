"""`python app.py` as a new user runs it on a fresh clone with no display: the default scene,
denoised where Open Image Denoise is installed, the raw render beside it, and no warnings.

The full run works on a copy of the project's files in a temporary folder (the default output
folder is inside the project: a test must not write there)."""
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import app
from renderer.output.denoise import unavailable_reason

ROOT = Path(__file__).resolve().parents[2]
# What a fresh clone does not have, or the first run does not need.
NOT_COPIED = (".git", ".venv", "out", "reports", "screenshots", "__pycache__", ".pytest_cache", "*.egg-info",
              "imgui.ini", "docs", "tests")
WARNING = re.compile(r"warn|^\[W ", re.IGNORECASE)


def no_display_env() -> dict[str, str]:
    import os

    return {key: value for key, value in os.environ.items() if key not in ("DISPLAY", "WAYLAND_DISPLAY")}


def high_frequency(path: Path) -> float:
    """Mean absolute difference of neighbouring pixels: the grain of the noise, mostly."""
    with Image.open(path) as image:
        pixels = np.asarray(image.convert("RGB"), dtype=np.float64)
    return float(np.abs(np.diff(pixels, axis=0)).mean() + np.abs(np.diff(pixels, axis=1)).mean())


def test_a_fresh_clone_without_a_display_writes_the_best_image_it_can(tmp_path):
    clone = tmp_path / "lantern"
    shutil.copytree(ROOT, clone, ignore=shutil.ignore_patterns(*NOT_COPIED), symlinks=True)
    proc = subprocess.run([sys.executable, "app.py"], cwd=clone, env=no_display_env(), capture_output=True,
                          text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    lines = [line for text in (proc.stdout, proc.stderr) for line in re.split(r"[\r\n]", text)]
    assert not [line for line in lines if WARNING.search(line)], proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    written = re.findall(r"^(.+\.png)  \((.*)\)$", proc.stdout, re.MULTILINE)
    image = Path(written[0][0])
    assert image.parent == clone / "out" and image.is_file(), proc.stdout  # in the copy, not the project
    reason = unavailable_reason()
    (said,) = [line for line in proc.stderr.splitlines() if line.startswith("no display:")]
    if reason is None:
        assert "the image will be denoised" in said
        assert re.fullmatch(r"32 spp in [\d.]+ s, denoised in [\d.]+ s", written[0][1]), written
        raw = image.with_name(image.stem + ".raw.png")
        assert written[1] == (str(raw), "the raw render, before denoising") and raw.is_file()
        with Image.open(image) as denoised, Image.open(raw) as noisy:
            assert denoised.text["denoised"] == "Intel Open Image Denoise" and "denoised" not in noisy.text
            assert denoised.size == noisy.size and denoised.text["spp"] == noisy.text["spp"] == "32"
        assert high_frequency(image) < 0.7 * high_frequency(raw)  # really denoised: the grain is gone
    else:
        assert said.endswith(f"not denoised: {reason}")
        assert len(written) == 1 and "denoised" not in written[0][1]
    assert sorted(p.name for p in image.parent.iterdir()) == sorted(Path(p).name for p, _ in written)


# --- what the first run asks for (no rendering) ------------------------------------------------


@pytest.fixture
def first_run(monkeypatch):
    """app.main without a display, the render command replaced by a recorder of its options."""
    import renderer.commands.render

    for name in ("DISPLAY", "WAYLAND_DISPLAY"):
        monkeypatch.delenv(name, raising=False)
    asked = []
    monkeypatch.setattr(renderer.commands.render, "run_render", lambda args, stop: asked.append(args) or 0)
    return asked


@pytest.mark.skipif(unavailable_reason() is not None, reason="pyoidn is not installed here")
def test_the_first_run_renders_the_default_scene_denoised(first_run, capsys):
    assert app.main([]) == 0
    (args,) = first_run
    assert (args.command, args.scene, args.spp, args.denoise) == ("render", "showcase", 32, True)
    assert "denoised" in capsys.readouterr().err


def test_without_pyoidn_the_first_run_says_why_it_is_not_denoised(first_run, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyoidn", None)  # `import pyoidn` fails as if it were not installed
    assert app.main([]) == 0
    (args,) = first_run
    assert args.denoise is False
    err = capsys.readouterr().err
    assert "not denoised: denoising needs the pyoidn package" in err and len(err.splitlines()) == 1


def test_no_denoise_keeps_the_first_run_raw(first_run, capsys):
    assert app.main(["--no-denoise"]) == 0
    (args,) = first_run
    assert args.denoise is False and "--no-denoise" in capsys.readouterr().err


def test_no_denoise_before_a_command_is_a_one_line_error(first_run, capsys):
    assert app.main(["--no-denoise", "render", "cornell_box"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --no-denoise before a command") and len(err.splitlines()) == 1
    assert first_run == []

"""Every file `app.py render` writes is known writable before anything renders, and checkpoints
may have any name but replace only checkpoints.

A folder can look writable and still refuse every new file: /proc takes no files, whatever its
mode says and for root too (CI runs as root, whose permission checks all pass). So the check
creates, and removes, the temporary file the atomic write will create; these tests make the
permission check pass (as it does for root) and leave the file system to refuse.
"""
import os
import subprocess
import sys
from pathlib import Path

import pytest

import app
from renderer.commands.headless import check_writable
from renderer.output.checkpoint import read_header, save_checkpoint
from renderer.output.denoise import unavailable_reason
from tests.output.checkpoint_helpers import film_state, header_for

ROOT = Path(__file__).resolve().parents[2]
PROC = Path("/proc")
needs_proc = pytest.mark.skipif(not (PROC / "self").is_dir(), reason="needs Linux's /proc")
needs_oidn = pytest.mark.skipif(unavailable_reason() is not None, reason="pyoidn is not installed here")


@pytest.fixture
def refused_before_rendering(monkeypatch):
    """Fails the test if the command starts Taichi: every refusal here comes before that."""
    import renderer.runtime.arch

    def started(*args, **kwargs):
        raise AssertionError("Taichi was started: the output should have been refused before")

    monkeypatch.setattr(renderer.runtime.arch, "init_taichi", started)


@pytest.fixture
def permissions_pass(monkeypatch):
    """os.access says yes to everything, as it does for root."""
    monkeypatch.setattr(os, "access", lambda *args, **kwargs: True)


def one_line_error(capsys, argv) -> str:
    code = app.main(argv)
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith("error:")]
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@needs_proc
@pytest.mark.parametrize("argv, named, problem", [
    (["--out", "/proc/x.png"], "/proc/x.png", "cannot create a file in /proc"),
    (["--out", "/proc/new/x.png"], "/proc/new/x.png", "cannot create the folder /proc/new"),
    (["--variance", "/proc/v.exr"], "/proc/v.exr", "cannot create a file in /proc"),
    (["--checkpoint", "/proc/run.ckpt"], "/proc/run.ckpt", "cannot create a file in /proc"),
    (["--frames", "0:1", "--out", "/proc/f_####.png"], "/proc/f_0000.png", "cannot create a file in /proc"),
    (["--frames", "0:1", "--out", "/proc/frames/f_####.png"], "/proc/frames/f_0000.png",
     "cannot create the folder /proc/frames"),
    (["--frames", "0:1", "--video", "/proc/v.mp4"], "/proc/v.mp4", "cannot create a file in /proc"),
])
def test_outputs_where_no_file_can_be_created_are_refused(tmp_path, capsys, refused_before_rendering,
                                                          permissions_pass, argv, named, problem):
    out = [] if "--out" in argv else ["--out", str(tmp_path / ("f_####.png" if "--frames" in argv else "a.exr"))]
    line = one_line_error(capsys, ["render", "cornell_box", "--size", "8x8", "--spp", "1", *out, *argv])
    assert line.startswith(f"error: {named}: {problem}"), line


@pytest.mark.parametrize("argv, beside", [
    (["--aovs"], "a.aovs.exr"),  # the AOVs of a .png go beside it
    pytest.param(["--denoise"], "a.raw.png", marks=needs_oidn),  # a denoised render keeps its raw image beside it
])
def test_the_files_written_beside_out_are_checked_too(tmp_path, capsys, refused_before_rendering, argv, beside):
    (tmp_path / beside).mkdir()
    line = one_line_error(capsys, ["render", "cornell_box", "--out", str(tmp_path / "a.png"), *argv])
    assert line == f"error: {tmp_path / beside}: is a directory"


def test_the_check_leaves_nothing_behind(tmp_path):
    """The folders made to try a file there and the file itself are removed again."""
    check_writable(tmp_path / "new" / "deeper" / "a.png")
    (tmp_path / "old").mkdir()
    check_writable(tmp_path / "old" / "a.png")
    assert [p.relative_to(tmp_path) for p in tmp_path.rglob("*")] == [Path("old")]


@needs_proc
def test_an_unwritable_out_fails_at_once_not_after_rendering(tmp_path):
    """As a user meets it: one line and status 2 before any rendering; no traceback, no
    checkpoint announced beside an output that cannot be written."""
    proc = subprocess.run([sys.executable, str(ROOT / "app.py"), "render", "cornell_box", "--size", "64x64",
                           "--spp", "200", "--arch", "cpu", "--out", "/proc/x.png"],
                          capture_output=True, text=True, timeout=300)
    errors = [line for line in proc.stderr.splitlines() if line.startswith("error:")]
    assert proc.returncode == 2, proc.stderr
    assert len(errors) == 1 and errors[0].startswith("error: /proc/x.png: "), proc.stderr
    assert "Traceback" not in proc.stderr and "rendering" not in proc.stderr and "checkpoint" not in proc.stderr


# --- checkpoint names --------------------------------------------------------------------------


def plan(argv):
    from renderer.commands.render import plan_render

    return plan_render(app.build_parser().parse_args(["render", "cornell_box", *argv]))


@pytest.mark.parametrize("name", ["run.state", "run", "run.ckpt.bak"])
def test_a_checkpoint_may_have_any_name(tmp_path, name):
    path = tmp_path / name
    assert plan(["--out", str(tmp_path / "a.png"), "--checkpoint", str(path)]).checkpoints.path == path


def test_an_existing_checkpoint_of_any_name_may_be_replaced(tmp_path):
    path = tmp_path / "yesterday.bin"
    save_checkpoint(path, header_for(ROOT / "assets" / "scenes" / "cornell_box.toml"), film_state(24, 16, 1.0))
    assert plan(["--out", str(tmp_path / "a.png"), "--checkpoint", str(path)]).checkpoints.path == path


@pytest.mark.parametrize("what, content", [("image", None), ("text", b"notes"), ("empty", b""),
                                           ("zip", b"PK\x05\x06" + bytes(18))])
def test_a_file_that_is_not_a_checkpoint_is_never_replaced(tmp_path, capsys, refused_before_rendering, what,
                                                           content):
    """--checkpoint a.png for --out a.png, a slip of the keyboard: refused, the image untouched."""
    image = tmp_path / "a.png"
    if content is None:
        from renderer.output.image_io import write_png
        import numpy as np

        write_png(image, np.zeros((4, 4, 3), np.uint8))
    else:
        image.write_bytes(content)
    before = image.read_bytes()
    line = one_line_error(capsys, ["render", "cornell_box", "--out", str(tmp_path / "b.png"),
                                   "--checkpoint", str(image)])
    assert line.startswith(f"error: {image}: exists and is not a Lantern checkpoint; refusing to replace it")
    assert image.read_bytes() == before


def test_the_automatic_checkpoint_does_not_replace_a_stranger_either(tmp_path, capsys, refused_before_rendering):
    stranger = tmp_path / "a.png.ckpt"
    stranger.write_text("someone's file")
    line = one_line_error(capsys, ["render", "cornell_box", "--out", str(tmp_path / "a.png")])
    assert line.startswith(f"error: {stranger}: exists and is not a Lantern checkpoint; the automatic checkpoint")
    assert stranger.read_text() == "someone's file"


def test_a_checkpoint_without_the_ckpt_extension_is_written_and_resumed(tmp_path):
    """Through the command line: saved under the name given, and continued from it."""
    path = tmp_path / "state.bin"
    run = [sys.executable, str(ROOT / "app.py"), "render"]
    small = ["--size", "8x8", "--arch", "cpu", "--integrator", "path", "--max-depth", "2"]
    proc = subprocess.run([*run, "cornell_box", "--spp", "2", *small, "--out", str(tmp_path / "a.exr"),
                           "--checkpoint", str(path)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert read_header(path).spp_done == 2
    proc = subprocess.run([*run, "--resume", str(path), "--spp", "3"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "continuing at 2 spp" in proc.stderr and read_header(path).spp_done == 3

"""`app.py render` stopped by a signal, as a user stops it: a child process rendering a small scene.

SIGINT or SIGTERM after the first pass: the render stops at a pass boundary, the image so far is
written (finite, its spp in the file's metadata and in the printed line), the exit status is
128 + the signal, and nothing prints a traceback. A second Ctrl-C quits at once. A render stopped
with a checkpoint and continued with --resume gives the uninterrupted render's image bit for bit.
"""
import re
import signal
import sys
import time

import numpy as np
import OpenEXR
import pytest
from PIL import Image

from renderer.output.checkpoint import load_checkpoint, read_header
from renderer.film.accumulation import FilmState
from renderer.output.image_io import read_exr
from renderer.commands.interrupts import Interrupted, StopRequests
from renderer.film.pixel_slices import ROUND_SLICES, spp_text
from tests.output.checkpoint_helpers import ROOT, WatchedChild
from tests.scene_builder import furnace_toml

# 24x16 pixels of `path` at max depth 3: about a million samples a second on one core, so
# 8000 spp take seconds, and the first passes (1, 4, 16, ... pixel slices, 256 to a sample) take milliseconds.
SMALL = ["--size", "24x16", "--integrator", "path", "--max-depth", "3", "--arch", "cpu", "--seed", "5"]
PROGRESS = re.compile(r"\] (\d+(?:\.\d+)?)(?:/\d+)? spp")


@pytest.fixture
def scene(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(furnace_toml(env=0.8, albedo=0.6, max_depth=3))
    return str(path)


def render_child(*args) -> WatchedChild:
    return WatchedChild([sys.executable, str(ROOT / "app.py"), "render", *map(str, args)])


def spp_reported(stderr: str) -> float:
    found = PROGRESS.findall(stderr)
    return float(found[-1]) if found else 0.0


def past_first_pass(stderr: str) -> bool:
    return spp_reported(stderr) >= 2  # the first pass (1 spp, compiling) is done, and one more


def assert_no_traceback(child: WatchedChild):
    assert "Traceback" not in child.stderr and "Traceback" not in child.stdout, child.stderr


def assert_stopped_within_the_pass_in_flight(child: WatchedChild, signum: int):
    """The handler says it stops when it runs (between bytecodes: at the latest when the pass in
    flight returns); after that line the render loop shows at most that pass's progress, and
    starts no other pass. Counted in passes, this holds however slow or busy the machine."""
    parts = child.stderr.split(f"{signal.Signals(signum).name}: stopping after this pass")
    assert len(parts) == 2, child.stderr
    assert len(PROGRESS.findall(parts[1])) <= 1, parts[1]


@pytest.mark.parametrize("signum, code, name", [(signal.SIGINT, 130, "a.png"), (signal.SIGTERM, 143, "a.exr")])
def test_a_signal_stops_at_a_pass_and_writes_the_image_so_far(tmp_path, scene, signum, code, name):
    out = tmp_path / name
    child = render_child(scene, "--time", 600, "--out", out, *SMALL)
    child.wait_for(past_first_pass, timeout=240)
    child.proc.send_signal(signum)
    # A signal ignored (the render going on for its 600 s) fails here. How soon the render stops
    # is counted in passes below, not in seconds, which a busy machine stretches.
    assert child.finish(timeout=60) == code, child.stderr
    assert_no_traceback(child)
    assert_stopped_within_the_pass_in_flight(child, signum)
    line = [l for l in child.stdout.splitlines() if l.startswith(f"{out}  (")]
    assert len(line) == 1 and "interrupted" in line[0], child.stdout
    shown = re.search(r"\((\d+(?:\.\d+)?) spp", line[0]).group(1)  # '12', or '12.34' within a round
    spp = float(shown)
    assert spp >= 2
    if name.endswith(".png"):
        with Image.open(out) as image:
            assert image.text["spp"] == shown and image.text["status"] == "interrupted"
            pixels = np.asarray(image)
        assert pixels.shape == (16, 24, 3) and pixels.max() > 0
    else:
        with OpenEXR.File(str(out)) as exr:
            assert exr.header()["spp"] == shown and exr.header()["status"] == "interrupted"
        pixels = read_exr(out)
        assert np.isfinite(pixels).all() and pixels.max() > 0
    # --time 600 is a long render: its automatic checkpoint was announced, and kept for --resume.
    checkpoint = tmp_path / (name + ".ckpt")
    assert f"checkpointing to {checkpoint}" in child.stderr
    header = read_header(checkpoint)
    assert spp_text(header.spp_done + header.slices_in_round / ROUND_SLICES) == shown


def test_a_second_ctrl_c_quits_at_once(tmp_path):
    """The first Ctrl-C's work is made long (a 1024x1024 film: its PNG, variance and checkpoint take
    about two seconds to write here); the second Ctrl-C, sent as soon as the first is acknowledged,
    ends the process before it has written any of them."""
    scene = tmp_path / "ball.toml"
    scene.write_text(furnace_toml(floor=False))  # most rays miss: cheap passes of a large film
    out, variance, checkpoint = tmp_path / "big.png", tmp_path / "big_var.exr", tmp_path / "big.ckpt"
    child = render_child(scene, "--spp", 100000, "--size", "1024x1024", "--integrator", "normals", "--arch", "cpu",
                         "--out", out, "--variance", variance, "--checkpoint", checkpoint)
    child.wait_for(past_first_pass, timeout=240)
    child.proc.send_signal(signal.SIGINT)
    child.wait_for(lambda err: "Ctrl-C again" in err, timeout=60)
    child.proc.send_signal(signal.SIGINT)
    # (a hang fails here; "at once" is not measured in seconds, which a busy machine stretches,
    # but by what was left undone: none of the three files the first Ctrl-C began to write)
    assert child.finish(timeout=60) == 130, child.stderr
    assert_no_traceback(child)
    assert "quitting now" in child.stderr
    assert not out.exists() and not variance.exists() and not checkpoint.exists()  # it did not wait


@pytest.mark.parametrize("packets", [0, 4])
def test_resume_after_a_real_interrupt_is_bit_identical(tmp_path, scene, packets):
    """With --packets, on a mesh scene: the checkpoint keeps the packet width, and the render
    continues in packets of it."""
    spp, extra = 8000, []
    if packets:
        scene, spp, extra = "cornell_box", 40000, ["--packets", packets]  # (faster a sample: more of them)
    reference, whole = tmp_path / "whole.exr", tmp_path / "whole.ckpt"
    child = render_child(scene, "--spp", spp, "--out", reference, "--checkpoint", whole, *SMALL, *extra)
    assert child.finish(timeout=300) == 0, child.stderr

    part, checkpoint = tmp_path / "part.exr", tmp_path / "part.ckpt"
    child = render_child(scene, "--spp", spp, "--out", part, "--checkpoint", checkpoint, *SMALL, *extra)
    child.wait_for(past_first_pass, timeout=240)
    child.proc.send_signal(signal.SIGINT)
    assert child.finish(timeout=60) == 130, child.stderr
    header = read_header(checkpoint)
    stopped_at = spp_text(header.spp_done + header.slices_in_round / ROUND_SLICES)
    assert 2 <= header.spp_done < spp
    assert f"checkpoint at {stopped_at} spp" in child.stdout

    final = tmp_path / "final.exr"  # everything else comes from the checkpoint
    child = render_child("--resume", checkpoint, "--out", final)
    assert child.finish(timeout=300) == 0, child.stderr
    assert f"continuing at {stopped_at} spp" in child.stderr
    assert (f"packets of {packets} rays: taken" in child.stderr) == bool(packets)
    np.testing.assert_array_equal(read_exr(final), read_exr(reference))
    (h1, continued), (h2, uninterrupted) = load_checkpoint(checkpoint), load_checkpoint(whole)
    assert h1.spp_done == h2.spp_done == spp
    for name, _, _ in FilmState.ARRAYS:
        np.testing.assert_array_equal(getattr(continued, name), getattr(uninterrupted, name), err_msg=name)


def test_stop_requests_defer_then_quit(capsys):
    """The handler itself, with real signals to this process: before defer() a signal raises
    Interrupted; after it, the first is a request and the second calls quit_now(128 + signal)."""
    import os

    quits = []
    before = (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM))  # SIG_IGN in a background job
    with StopRequests(quit_now=quits.append) as stop:
        with pytest.raises(Interrupted) as raised:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(1)  # the handler runs at the next bytecode; never reached
        assert raised.value.signum == signal.SIGTERM and not stop.requested
        stop.defer()
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.01)
        assert stop.requested and stop.exit_code == 130 and quits == []
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.01)
        assert quits == [143]
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before  # restored


@pytest.mark.vulkan
def test_resume_is_bit_identical_on_vulkan(tmp_path, scene):
    """The film's state loads through an ndarray kernel valid on GPU back-ends: a render continued
    on Vulkan (the checkpoint's back-end, by default) equals the uninterrupted Vulkan render."""
    from tests.test_vulkan import vulkan_available

    if not vulkan_available():
        pytest.skip("no Vulkan driver (install libvulkan1 mesa-vulkan-drivers)")
    on_vulkan = [a if a != "cpu" else "vulkan" for a in SMALL]
    reference, part, final = tmp_path / "whole.exr", tmp_path / "part.exr", tmp_path / "final.exr"
    checkpoint = tmp_path / "part.ckpt"
    for args in ((scene, "--spp", 40, "--out", reference, *on_vulkan),
                 (scene, "--spp", 15, "--out", part, "--checkpoint", checkpoint, *on_vulkan),
                 ("--resume", checkpoint, "--spp", 40, "--out", final)):
        child = render_child(*args)
        assert child.finish(timeout=600) == 0, child.stderr
    assert read_header(checkpoint).arch == "vulkan" and read_header(checkpoint).spp_done == 40
    np.testing.assert_array_equal(read_exr(final), read_exr(reference))

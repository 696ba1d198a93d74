"""Every file Lantern writes is replaced whole or not at all: a failure or a kill between writing and
renaming leaves the previous file intact and readable."""
import os
import random
import signal
import stat
import time

import numpy as np
import pytest

import renderer.output.atomic_write as atomic_write
from renderer.output.atomic_write import atomic_output, write_text_atomic
from renderer.bench.common import pyplot, save_figure, write_json
from renderer.output.checkpoint import load_checkpoint, save_checkpoint
from renderer.output.image_io import read_exr, write_exr, write_png
from tests.output.checkpoint_helpers import WatchedChild, film_state, header_for, python_child
from tests.scene_builder import furnace_toml


def leftovers(directory):
    return sorted(p.name for p in directory.iterdir() if atomic_write.TEMPORARY_MARKER in p.name)


def test_atomic_output_replaces_the_file_with_ordinary_permissions(tmp_path):
    target = tmp_path / "deep" / "er" / "a.txt"  # parents are created
    write_text_atomic(target, "first")
    write_text_atomic(target, "second")
    assert target.read_text() == "second"
    assert leftovers(target.parent) == []
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~umask  # as open() would create it


def test_a_failing_writer_leaves_the_previous_file_and_no_temporary(tmp_path):
    target = tmp_path / "a.bin"
    target.write_bytes(b"previous")
    with pytest.raises(RuntimeError, match="disk full"):
        with atomic_output(target) as temporary:
            temporary.write_bytes(b"half of the new")
            raise RuntimeError("disk full")
    assert target.read_bytes() == b"previous"
    assert leftovers(tmp_path) == []


def _figure():
    fig = pyplot().figure()
    fig.gca().plot([0, 1], [1, 0])
    return fig


# Each writer of the project, with what it writes and how to read it back.
WRITERS = {
    "png": (lambda p, v: write_png(p, np.full((4, 5, 3), v, np.float32)), "a.png"),
    "exr": (lambda p, v: write_exr(p, np.full((4, 5, 3), v, np.float32)), "a.exr"),
    "checkpoint": (lambda p, v: save_checkpoint(p, header_for(p.parent / "s.toml", width=5, height=4),
                                                film_state(5, 4, v)), "a.ckpt"),
    "bench json": (lambda p, v: write_json(p, {"value": v}), "a.json"),
    "bench figure": (lambda p, v: save_figure(_figure(), p), "a.png"),
}


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_every_writer_goes_through_the_atomic_rename(tmp_path, monkeypatch, writer):
    """A rename that fails (as if the process died just before it) must leave the previous file
    byte for byte, and no temporary: so the writer wrote to a temporary name, not to the file."""
    (tmp_path / "s.toml").write_text(furnace_toml())
    write, name = WRITERS[writer]
    target = tmp_path / name
    write(target, 0.25)
    before = target.read_bytes()
    replaced = []

    def failing_replace(src, dst):
        replaced.append((os.fspath(src), os.fspath(dst)))
        raise OSError("simulated crash before the rename")

    monkeypatch.setattr(atomic_write.os, "replace", failing_replace)
    with pytest.raises(OSError, match="simulated crash"):
        write(target, 0.75)
    assert replaced and replaced[0][1] == os.fspath(target)
    assert target.read_bytes() == before
    assert leftovers(tmp_path) == []


def test_image_metadata_is_written(tmp_path):
    from PIL import Image
    import OpenEXR

    write_png(tmp_path / "a.png", np.zeros((2, 3, 3), np.float32), {"spp": "17", "status": "interrupted"})
    with Image.open(tmp_path / "a.png") as image:
        assert image.text["spp"] == "17" and image.text["status"] == "interrupted"
    pixels = np.arange(18, dtype=np.float32).reshape(2, 3, 3)
    write_exr(tmp_path / "a.exr", pixels, {"spp": "17"})
    with OpenEXR.File(str(tmp_path / "a.exr")) as exr:
        assert exr.header()["spp"] == "17"
    np.testing.assert_array_equal(read_exr(tmp_path / "a.exr"), pixels)


SAVE_WITH_A_CRASH_BEFORE_THE_RENAME = """
import os, signal
import renderer.output.atomic_write as atomic_write
from renderer.output.checkpoint import save_checkpoint
from tests.output.checkpoint_helpers import film_state, header_for
target, scene = sys.argv[1], sys.argv[2]
# The kill lands after the temporary file is complete and synced, before it is renamed.
atomic_write.os.replace = lambda src, dst: os.kill(os.getpid(), signal.SIGKILL)
save_checkpoint(target, header_for(scene, spp_done=99), film_state(24, 16, 99.0))
"""


def test_kill_between_temporary_and_rename_keeps_the_previous_checkpoint(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text(furnace_toml())
    target = tmp_path / "run.ckpt"
    save_checkpoint(target, header_for(scene, spp_done=4), film_state(24, 16, 4.0))
    proc = WatchedChild(python_child(SAVE_WITH_A_CRASH_BEFORE_THE_RENAME, str(target), str(scene)))
    assert proc.finish(timeout=120) == -signal.SIGKILL, proc.stderr
    header, state = load_checkpoint(target)
    assert header.spp_done == 4 and (state.mean == 4.0).all() and (state.count == 4).all()
    assert len(leftovers(tmp_path)) == 1  # the complete new file, never renamed


SAVE_IN_A_LOOP = """
from renderer.output.checkpoint import save_checkpoint
from tests.output.checkpoint_helpers import film_state, header_for
target, scene = sys.argv[1], sys.argv[2]
k = 1
while True:
    save_checkpoint(target, header_for(scene, width=512, height=512, spp_done=k), film_state(512, 512, float(k)))
    print(k, file=sys.stderr, flush=True)
    k += 1
"""


def test_kill_9_at_random_moments_of_large_checkpoint_writes(tmp_path):
    """A child rewrites an 8 MB checkpoint in a loop and is killed -9 at random moments: the file is
    always a whole checkpoint, the last one announced or the one after it."""
    scene = tmp_path / "s.toml"
    scene.write_text(furnace_toml())
    target = tmp_path / "loop.ckpt"
    rng = random.Random(5)
    for _ in range(4):
        child = WatchedChild(python_child(SAVE_IN_A_LOOP, str(target), str(scene)))
        child.wait_for(lambda err: "1" in err.splitlines(), timeout=120)
        time.sleep(rng.uniform(0.05, 0.4))
        child.proc.send_signal(signal.SIGKILL)
        assert child.finish(timeout=30) == -signal.SIGKILL
        announced = [int(line) for line in child.stderr.split() if line.isdigit()]
        header, state = load_checkpoint(target)
        assert header.spp_done in (announced[-1], announced[-1] + 1), (header.spp_done, announced[-3:])
        assert (state.mean == header.spp_done).all() and (state.count == header.spp_done).all()

"""`app.py render SCENE --turntable SECONDS` as a user runs it (a child process): the frames of one
turn, named by the --out pattern, each the view of the scene's camera turned about the vertical
axis through the scene's centre (an SDF scene's look_at point), counter-clockwise seen from above.

The scene: a red ball and a blue box on a floor under a sky that changes with height only (nothing
but the objects tells the views apart; under a constant sky, floor pixels that no path finds
occluded would have no variance), seen from four quarter turns (--turntable 1 --fps 4). Each frame is held by
the suite's z-tests (tests/stats/image_tests.py; alpha = 0.01) against a render made here through
the Renderer API from a camera turned by this test's own arithmetic, on another seed: it must agree
with its own quarter turn and differ from the three others (a camera that does not move, turns the
other way or by the wrong angle fails). A second run, frames 2 to 4 of the same turntable, ends at a
whole turn: its frame 4 is frame 0 again, and its frames 2 and 3 those of the first run, bit for bit
(a frame is a still render of its camera, with the job's seed, whichever frames a run renders).
"""
from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import OpenEXR
import pytest

from renderer.camera import CameraFrame
from renderer.output.image_io import read_exr
from renderer.renderer import Renderer
from renderer.scene import load_scene
from tests.commands.test_cli import ROOT
from tests.stats.image_tests import assert_agree, pixel_z_test

SCENE = """[scene]
geometry = "sdf"
[camera]
position = [0.0, 1.2, 3.0]
look_at = [0.0, 0.4, 0.0]
fov = 50
[render]
width = 32
height = 24
max_depth = 3
integrator = "path"
[environment]
type = "sky"
[materials.floor]
type = "diffuse"
base_color = [0.5, 0.5, 0.5]
[materials.red]
type = "diffuse"
base_color = [0.8, 0.1, 0.1]
[materials.blue]
type = "diffuse"
base_color = [0.1, 0.2, 0.8]
[[objects]]
type = "plane"
material = "floor"
[[objects]]
type = "sphere"
material = "red"
radius = 0.35
translate = [0.9, 0.35, 0.0]
[[objects]]
type = "box"
material = "blue"
size = [0.5, 0.8, 0.5]
translate = [0.0, 0.4, -0.9]
"""
SECONDS, FPS = 1, 4  # four frames: quarter turns
SPP = 64  # each frame's
REFERENCE_SPP = 4 * SPP  # the references': their noise adds a quarter to the frames' variance


def render_frames(scene, out_dir, *extra) -> subprocess.CompletedProcess:
    proc = subprocess.run([sys.executable, str(ROOT / "app.py"), "render", str(scene), "--turntable", str(SECONDS),
                           "--fps", str(FPS), "--spp", str(SPP), "--seed", "1", "--arch", "cpu", "--optimize", "compile",
                           "--out", str(out_dir / "frame_##.exr"), *extra],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return proc


def turned_camera(spec, centre, turns: float) -> CameraFrame:
    """The scene's camera turned by `turns` of a whole turn about the vertical line through
    `centre`, counter-clockwise seen from above (+z goes to +x at a quarter turn)."""
    angle = 2.0 * math.pi * turns
    c, s = math.cos(angle), math.sin(angle)

    def turn(point):
        x, y, z = np.subtract(point, centre)
        return tuple(np.add(centre, (c * x + s * z, y, -s * x + c * z)))

    return CameraFrame.look_at(turn(spec.position), turn(spec.look_at), spec.up, spec.fov, spec.aperture,
                               spec.focus_distance)


def test_a_turntable_renders_the_frames_of_one_turn_each_from_its_turned_camera(tmp_path):
    scene_path = tmp_path / "orbit.toml"
    scene_path.write_text(SCENE)
    first = tmp_path / "turn"
    proc = render_frames(scene_path, first)

    # The frames of one turn: 0 to SECONDS * FPS - 1, named by the pattern, one line each in order.
    names = [f"frame_{i:02d}.exr" for i in range(SECONDS * FPS)]
    assert sorted(p.name for p in first.iterdir()) == names
    lines = [line for line in proc.stdout.splitlines() if "  (frame " in line]
    assert [line.split("  (")[0] for line in lines] == [str(first / name) for name in names]
    assert all(f"(frame {i}: {SPP} spp in" in line for i, line in enumerate(lines))
    assert f"frames 0 to 3 at {FPS} fps, a turntable of {SECONDS} s about (0, 0.4, 0)" in proc.stderr
    for i, name in enumerate(names):
        with OpenEXR.File(str(first / name)) as exr:
            header = exr.header()
            assert (header["frame"], header["time"], header["spp"]) == (str(i), f"{i / FPS:g}", str(SPP))
    frames = [read_exr(first / name).astype(np.float64) for name in names]
    assert all(f.shape == (24, 32, 3) and np.isfinite(f).all() for f in frames)

    # The references: the camera turned by a quarter turn per frame, another seed. A frame's own
    # variance of each pixel's mean (what --variance writes for a still; animations do not write
    # it) is that of the same render made here, the frame's seed and spp from the turned camera.
    # (The references' variance cannot stand in for it: a floor pixel's rare paths that reach the
    # red ball make its distribution heavy-tailed, and 256 samples may miss what 64 met.)
    scene = load_scene(scene_path)
    renderer = Renderer(scene, (32, 24))

    def render_here(camera, spp, seed):
        renderer.reset()
        renderer.render(camera, spp, "path", scene.render.max_depth, seed)
        return (renderer.film.mean_image().astype(np.float64),
                renderer.film.variance_of_mean_image().astype(np.float64))

    cameras = [turned_camera(scene.camera, scene.camera.look_at, i / len(names)) for i in range(len(names))]
    references = [render_here(camera, REFERENCE_SPP, 2) for camera in cameras]
    for i, frame in enumerate(frames):
        own = (frame, render_here(cameras[i], SPP, 1)[1])
        assert_agree(own, references[i], (f"frame {i}", f"the camera turned {i}/4"))
        for j, other in enumerate(references):
            if j != i:  # a quarter turn away changes the view far beyond the noise
                passed, fraction, *_ = pixel_z_test(*own, *other)
                assert not passed and fraction < 0.9, (i, j, fraction)

    # Frames 2 to 4 of the same turntable: frame 4 is at the end of the turn, where frame 0 is.
    second = tmp_path / "on"
    render_frames(scene_path, second, "--frames", "2:4")
    assert sorted(p.name for p in second.iterdir()) == ["frame_02.exr", "frame_03.exr", "frame_04.exr"]
    again = {i: read_exr(second / f"frame_{i:02d}.exr") for i in (2, 3, 4)}
    np.testing.assert_array_equal(again[4], frames[0])
    for i in (2, 3):
        np.testing.assert_array_equal(again[i], frames[i])

"""`app.py render --frames` as a user runs it (in-process, through app.main): frames written per the
--out pattern, each a still render of its camera (the first one bit for bit), a video of the frames,
a stop request after a frame, and every bad option refused in one line before Taichi starts."""
from __future__ import annotations

import signal
import sys

import imageio.v2 as imageio
import numpy as np
import pytest
from PIL import Image

import app
from renderer.commands.animation.camera_path import CameraPath
from renderer.commands.animation.command import run_animation
from renderer.commands.headless import RenderJob, render
from renderer.output.image_io import read_exr
from renderer.commands.interrupts import StopRequests
from renderer.scene import load_scene
from tests.commands.test_cli import ROOT, no_rendering, one_line_error, run_main  # noqa: F401 (a fixture)

SCENE = str(ROOT / "tests" / "data" / "camera_path.toml")  # 32x24, 2 spp of `path`, max depth 3
CPU = ["--arch", "cpu"]


def test_three_frames_differ_and_the_first_is_the_still_render_at_time_0(tmp_path, capsys):
    code, out, _ = run_main(["render", SCENE, "--frames", "0:2", "--fps", "2", "--out",
                             str(tmp_path / "anim" / "f_###.exr"), *CPU], capsys)
    assert code == 0
    frames = [tmp_path / "anim" / f"f_{i:03d}.exr" for i in range(3)]
    lines = [line for line in out.splitlines() if "  (frame " in line]  # (Taichi says where it starts too)
    assert [line.split("  (")[0] for line in lines] == [str(f) for f in frames]
    assert all(f"(frame {i}: 2 spp in" in line for i, line in enumerate(lines))
    images = [read_exr(f) for f in frames]
    assert all(image.shape == (24, 32, 3) and np.isfinite(image).all() for image in images)
    for a, b in ((0, 1), (1, 2), (0, 2)):  # the camera moves (times 0, 0.5 and 1 s)
        assert np.abs(images[a] - images[b]).mean() > 0.01, (a, b)
    # [camera] is the first keyframe: the still render of the scene is frame 0, bit for bit.
    code, _, _ = run_main(["render", SCENE, "--out", str(tmp_path / "still.exr"), *CPU], capsys)
    assert code == 0
    np.testing.assert_array_equal(read_exr(tmp_path / "still.exr"), images[0])
    # Frame 1 (after frame 0 on the same Renderer) is a fresh still render with its camera too.
    scene = load_scene(SCENE)
    fresh = render(scene, RenderJob(), camera=CameraPath(scene.camera).camera_at(0.5))
    np.testing.assert_array_equal(fresh.image, images[1])


def test_png_frames_and_a_video_of_them(tmp_path, capsys):
    video = tmp_path / "clip.mp4"
    code, out, _ = run_main(["render", SCENE, "--frames", "3:5", "--fps", "4", "--out", str(tmp_path / "f_#.png"),
                             "--video", str(video), *CPU], capsys)
    assert code == 0 and f"{video}  (3 frames at 4 fps)" in out
    for i in (3, 4, 5):
        with Image.open(tmp_path / f"f_{i}.png") as image:
            assert image.size == (32, 24)
            assert image.text["frame"] == str(i) and image.text["time"] == f"{i / 4:g}"
            assert image.text["status"] == "complete" and image.text["spp"] == "2"
    with imageio.get_reader(video, format="FFMPEG") as reader:
        shown = [frame for frame in reader]
        assert reader.get_meta_data()["fps"] == 4
    assert len(shown) == 3 and shown[0].shape == (24, 32, 3)


class StopAfterFirstFrame(StopRequests):
    """A Ctrl-C that arrives in the second frame, after its first pass: the render loop asks
    `requested` before every pass, and the request comes at the second question once frame 0's
    file exists."""

    def __init__(self, first_frame):
        super().__init__()
        self.first_frame = first_frame
        self.asked_since = 0

    @property
    def requested(self) -> bool:
        if self.signum is None and self.first_frame.exists():
            self.asked_since += 1
            if self.asked_since == 2:
                self._handle(signal.SIGINT, None)
        return self.signum is not None


def test_a_stop_request_ends_the_frame_in_progress_writes_it_and_renders_no_more(tmp_path, capsys):
    args = app.build_parser().parse_args(["render", SCENE, "--frames", "0:2", "--out", str(tmp_path / "f_#.png"),
                                          "--video", str(tmp_path / "v.mp4"), *CPU])
    stop = StopAfterFirstFrame(tmp_path / "f_0.png")
    assert run_animation(args, stop) == 130
    out = capsys.readouterr().out
    assert not (tmp_path / "f_2.png").exists()
    with Image.open(tmp_path / "f_0.png") as first, Image.open(tmp_path / "f_1.png") as stopped:
        assert first.text["status"] == "complete" and stopped.text["status"] == "interrupted"
    assert "frame 1: 0 spp" in out and "interrupted" in out and f"{tmp_path / 'v.mp4'}  (2 frames" in out


@pytest.mark.parametrize("argv, expected", [
    (["--frames", "a:b"], "--frames a:b: 'a' is not a whole frame number"),
    (["--frames", "1.5:3"], "'1.5' is not a whole frame number"),
    (["--frames=-1:3"], "--frames -1:3: frame numbers start at 0"),
    (["--frames", "4:2"], "--frames 4:2: the first frame 4 is after the last 2"),
    (["--frames", "7"], "--frames 7: expected A:B"),
    (["--frames", "0:1000000"], "--frames 0:1000000: at most 1,000,000 frames in one run"),
    (["--turntable", "1e6"], "--turntable 1e+06 at 24 fps: 24,000,000 frames, more than the 1,000,000 of one run"),
    (["--frames", "0:2", "--out", "{d}/frame.png"], "frame.png: --out of an animation needs one run of '#'"),
    (["--frames", "0:2", "--out", "{d}/f_##_##.png"], "found 2 runs"),
    (["--frames", "0:2", "--out", "{d}/#/f_#.png"], "found a '#' in a folder name"),
    (["--frames", "0:2", "--out", "{d}/f_#.jpg"], "unsupported output extension '.jpg'"),
    (["--frames", "0:2", "--video", "{d}/v.gif"], "v.gif: unsupported video extension '.gif' (use .mp4, .mov or .mkv)"),
    (["--frames", "0:2", "--resume", "{d}/x.ckpt"], "--resume: animations are not checkpointed (a frame is a short"),
    (["--frames", "0:2", "--checkpoint", "{d}/x.ckpt"], "--checkpoint: animations are not checkpointed"),
    (["--turntable", "2", "--variance", "{d}/v.exr"], "--variance: not written for animation frames"),
    (["--frames", "0:2", "--aovs"], "--aovs: not written for animation frames"),
    (["--turntable", "0"], "argument --turntable: must be a positive number of seconds"),
    (["--frames", "0:2", "--fps=-24"], "argument --fps: must be a positive number"),
    (["--video", "{d}/v.mp4"], "--video is for animations: add --frames A:B or --turntable SECONDS"),
    (["--fps", "12"], "--fps is for animations: add --frames A:B or --turntable SECONDS"),
])
def test_bad_animation_options_are_one_line_errors_before_rendering(tmp_path, capsys, no_rendering, argv, expected):
    argv = [a.format(d=tmp_path) for a in argv]
    if "--out" not in argv:
        argv += ["--out", str(tmp_path / "f_#.png")]
    code, _, err = run_main(["render", SCENE, *argv], capsys)
    line = one_line_error(err)
    assert code == 2 and expected in line, line


def test_a_missing_ffmpeg_is_one_line_before_rendering(tmp_path, capsys, no_rendering, monkeypatch):
    import imageio_ffmpeg

    def missing():
        raise RuntimeError("No ffmpeg exe could be found.\nInstall ffmpeg on your system.")

    monkeypatch.setattr(imageio_ffmpeg, "get_ffmpeg_exe", missing)
    code, _, err = run_main(["render", SCENE, "--frames", "0:2", "--out", str(tmp_path / "f_#.png"),
                             "--video", str(tmp_path / "v.mp4")], capsys)
    line = one_line_error(err)
    assert code == 2 and "v.mp4: cannot write a video: no ffmpeg executable found (No ffmpeg exe" in line, line


def test_frames_on_workers_without_the_distributed_module_are_one_line(tmp_path, capsys, no_rendering, monkeypatch):
    monkeypatch.setitem(sys.modules, "renderer.commands.distributed.frames", None)  # an import of it fails
    code, _, err = run_main(["render", SCENE, "--frames", "0:2", "--out", str(tmp_path / "f_#.png"),
                             "--workers", "2"], capsys)
    line = one_line_error(err)
    assert code == 2 and "--workers / --ray-address: frames cannot be rendered on Ray workers here" in line, line

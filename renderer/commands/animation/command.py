"""`app.py render --frames A:B` and `--turntable SECONDS`: an animation, a still render per frame.

Everything that can be checked is checked before Taichi starts (the frame range, the --out
pattern and its folder, the video's extension and ffmpeg, the scene, the job). Frame i is at
time i / fps on the scene's camera path (renderer/commands/animation/camera_path.py) or on a turntable
(turntable.py). Frames are written as they come, one line each; a stop signal ends the frame in
progress at a pass boundary, which is written if it has samples, and the exit status is the still
render's (128 + the signal). --video then assembles the frames written.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from renderer.commands.animation.camera_path import CameraPath
from renderer.commands.animation.frame_numbers import DEFAULT_FPS, FramePattern, parse_frame_range, turntable_frames
from renderer.commands.animation.frames import FrameRequest, FrameResult, LocalFrames
from renderer.commands.headless import RenderJob, RenderResult, check_output_path, display_tonemapper, image_metadata, save
from renderer.commands.interrupts import StopRequests
from renderer.scene.description import Scene

DEFAULT_OUT_DIR = Path(__file__).resolve().parents[3] / "out"


@dataclass
class AnimationPlan:
    """Everything an animation will do, decided and checked before Taichi starts."""

    scene: Scene
    job: RenderJob
    frames: FramePattern
    fps: float
    requests: list[FrameRequest]
    motion: str  # what moves the camera, for the first line
    video: Path | None
    arch: str
    optimize: str


def run_animation(args, stop: StopRequests) -> int:
    """The render command with --frames or --turntable; returns the exit status."""
    plan = plan_animation(args)
    source, where = frame_renderer(plan, args)
    first, last = plan.requests[0].index, plan.requests[-1].index
    print(f"rendering {plan.scene.name} with {plan.job.integrator} on {where}: frames {first} to {last} at "
          f"{plan.fps:g} fps, {plan.motion}", file=sys.stderr)
    written = []
    for result in source.render(plan.requests, stop):
        written.append(write_frame(plan, result))
    if not written:
        print("interrupted before the first frame had a sample: nothing written", file=sys.stderr)
    elif plan.video is not None:
        from renderer.commands.animation.video import write_video

        count = write_video(plan.video, (display_frame(plan, path) for path in written), plan.fps)
        print(f"{plan.video}  ({count} frames at {plan.fps:g} fps)")
    return stop.exit_code or 0


def plan_animation(args) -> AnimationPlan:
    """Read and check the options and the scene (one-line errors), and the camera of every frame."""
    from renderer.commands.animation.turntable import Turntable, orbit_centre
    from renderer.commands.render_job import check_denoising, job_from_arguments
    from renderer.scene.catalog import load_any, resolve_scene
    from renderer.scene.limits import check_film
    from renderer.scene.load_options import options_from_arguments

    _refuse_still_only_options(args)
    fps = args.fps if args.fps is not None else DEFAULT_FPS
    span = parse_frame_range(args.frames) if args.frames is not None else turntable_frames(args.turntable, fps)
    frames = FramePattern.parse(args.out) if args.out is not None else None  # (the default names the scene)
    if frames is not None:
        check_output_path(frames.path(span[0]))
    if args.video is not None:
        from renderer.commands.animation.video import check_video_path

        check_video_path(args.video)
    if args.scene is None:
        raise ValueError("render: give a SCENE")
    scene = load_any(resolve_scene(args.scene), options_from_arguments(args))
    job = job_from_arguments(args, scene, None)
    check_denoising(job)
    check_film(scene.path, *job.size, scene.model_files.options.budget,
               "--size" if args.size else "the scene's render.width x height", aovs=job.keeps_aovs)
    if frames is None:
        frames = FramePattern(DEFAULT_OUT_DIR / f"{scene.name}_{job.integrator}" / "frame_####.png")
        check_output_path(frames.path(span[0]))
    if args.turntable is not None:
        centre, what = orbit_centre(scene)
        motion = Turntable(scene.camera, centre, args.turntable, what)
    else:
        motion = CameraPath(scene.camera)
    requests = [FrameRequest(i, i / fps, motion.camera_at(i / fps)) for i in range(span[0], span[1] + 1)]
    return AnimationPlan(scene, job, frames, fps, requests, motion.describe(), args.video, args.arch or "auto",
                         args.optimize or "compile")


def frame_renderer(plan: AnimationPlan, args):
    """(what renders the frames, where): LocalFrames on this machine's Taichi, or with --workers or
    --ray-address renderer.commands.distributed.frames.RayFrames."""
    if getattr(args, "workers", None) or getattr(args, "ray_address", None):
        try:
            from renderer.commands.distributed.frames import RayFrames
        except ImportError as error:
            raise ValueError(f"--workers / --ray-address: frames cannot be rendered on Ray workers here "
                             f"({' '.join(str(error).split())})") from None
        return RayFrames(plan.scene, plan.job, args), "Ray workers"
    from renderer.runtime.arch import init_taichi

    return LocalFrames(plan.scene, plan.job), init_taichi(plan.arch, optimize=plan.optimize)


def write_frame(plan: AnimationPlan, frame: FrameResult) -> Path:
    """The frame's image file (its frame number and time in its metadata), and its line."""
    job = plan.job
    path = plan.frames.path(frame.index)
    as_render = RenderResult(frame.image, frame.spp, frame.seconds, frame.rejected, job.integrator,
                             interrupted=frame.interrupted)
    metadata = {**image_metadata(plan.scene, job, as_render), "frame": str(frame.index),
                "time": f"{frame.index / plan.fps:g}"}
    if job.denoise:
        metadata["denoised"] = "Intel Open Image Denoise"
    save(frame.image, path, job.exposure, display_tonemapper(job.integrator, job.tonemapper), metadata)
    rejected = f", {frame.rejected} non-finite samples dropped" if frame.rejected else ""
    stopped = ", interrupted" if frame.interrupted else ""
    denoised = ", denoised" if job.denoise else ""
    print(f"{path}  (frame {frame.index}: {frame.spp} spp in {frame.seconds:.1f} s{rejected}{stopped}{denoised})",
          flush=True)
    return path


def display_frame(plan: AnimationPlan, path: Path):
    """A written frame as the video shows it: a PNG's pixels, an EXR tone-mapped as a PNG would be."""
    if path.suffix.lower() == ".png":
        import imageio.v3 as iio

        return iio.imread(path)[..., :3]
    from renderer.output.image_io import read_exr
    from renderer.output.tonemap import tonemap_array

    job = plan.job
    return tonemap_array(read_exr(path), job.exposure, display_tonemapper(job.integrator, job.tonemapper))


def _refuse_still_only_options(args) -> None:
    """Options of still renders that animations do not take, each refused in one line."""
    if args.resume is not None or args.checkpoint is not None:
        option = "--resume" if args.resume is not None else "--checkpoint"
        raise ValueError(f"{option}: animations are not checkpointed (a frame is a short render; to finish an "
                         "interrupted animation, render the frames still missing with --frames)")
    if args.variance is not None:
        raise ValueError("--variance: not written for animation frames (render the frame as a still for it)")
    if args.aovs:
        raise ValueError("--aovs: not written for animation frames (render the frame as a still for them)")

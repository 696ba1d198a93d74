"""`app.py render`: options to files, with checkpoints, resumption and a clean stop on a signal.

Everything that can be checked is checked before Taichi starts: output paths (writable, not a
directory, a known extension), the checkpoint to resume (readable, same Lantern, same scene
files, compatible options). A stop signal during rendering ends the render at a pass boundary;
the image so far is written with its real spp, and the exit status is 128 + the signal's number.
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

from renderer.output.checkpoint import CHECKPOINT_EXTENSION, CheckpointHeader, is_checkpoint, load_checkpoint, \
    read_header, save_checkpoint, scene_fingerprint
from renderer.commands.headless import FilmSource
from renderer.commands.headless import (Checkpoints, RenderJob, RenderResult, Resume, check_output_path, check_variance_path,
                               check_writable, display_tonemapper, image_metadata, progress_bar, render, save,
                               save_variance)
from renderer.commands.interrupts import StopRequests
from renderer.commands.render_job import check_denoising, job_from_arguments
from renderer.runtime.optimize_choice import choose_for_render
from renderer.output.render_outputs import aovs_path, raw_path
from renderer.film.pixel_slices import ROUND_SLICES, spp_text
from renderer.scene.errors import SceneError
from renderer.scene.description import Scene
from renderer.runtime.version import lantern_version

DEFAULT_OUT_DIR = Path(__file__).resolve().parents[2] / "out"
# Renders expected to take longer than this get a checkpoint beside --out even without --checkpoint.
LONG_RENDER_SECONDS = 60.0
DEFAULT_CHECKPOINT_EVERY = 30.0
CPU_ARCHES = ("x64", "arm64")  # what Taichi calls its CPU back-ends


class CheckpointPolicy(Checkpoints):
    """Saves the film every `every` seconds of wall time. An automatic checkpoint (no --checkpoint)
    starts only once the render is expected to take longer than LONG_RENDER_SECONDS, and is
    removed when the render completes: it exists to survive an interruption."""

    def __init__(self, path: Path, every: float, header: CheckpointHeader, active: bool, stream=sys.stderr):
        self.path = path
        self.every = every
        self.automatic = header.automatic
        self.header = header
        self.active = active  # False: automatic, and not (yet) a long render
        self.stream = stream
        self.last_save = time.monotonic()

    def after_pass(self, film: FilmSource, spp_done: int, seconds_rendered: float, expected_seconds: float | None,
                   slices_in_round: int = 0) -> None:
        if not self.active:
            if expected_seconds is None or expected_seconds <= LONG_RENDER_SECONDS:
                return
            self.active = True
            self.last_save = time.monotonic()
            self._say(f"a long render (about {expected_seconds:.0f} s): checkpointing to {self.path} every "
                      f"{self.every:g} s; continue an interrupted render with: "
                      f"python app.py render --resume {self.path}")
        if time.monotonic() - self.last_save >= self.every:
            self.save(film, spp_done, seconds_rendered, slices_in_round)

    def save(self, film: FilmSource, spp_done: int, seconds_rendered: float, slices_in_round: int = 0) -> None:
        save_checkpoint(self.path, replace(self.header, spp_done=spp_done, slices_in_round=slices_in_round,
                                           seconds_rendered=seconds_rendered), film.state())
        self.last_save = time.monotonic()

    def finish(self, result: RenderResult) -> str | None:
        """The final save (or, for a completed automatic checkpoint, its removal); what was done."""
        if not self.active:
            return None
        if self.automatic and not result.interrupted:
            self.path.unlink(missing_ok=True)
            return None
        self.save(result.renderer, result.spp, result.seconds_rendered, result.slices_in_round)
        return f"{self.path}  (checkpoint at {result.spp_text()} spp; continue with: python app.py render --resume {self.path})"

    def _say(self, message: str) -> None:
        self.stream.write(f"\n{message}\n")
        self.stream.flush()


@dataclass
class RenderPlan:
    """Everything `render` will do, decided and checked before Taichi starts."""

    scene: Scene
    job: RenderJob
    out: Path
    variance: Path | None
    arch: str
    optimize: str
    checkpoints: CheckpointPolicy | None
    resume: Resume | None
    previous: CheckpointHeader | None  # the header of the checkpoint continued
    distributed: "DistributedOptions | None" = None  # Ray workers (renderer/commands/distributed/render.py)


def run_render(args, stop: StopRequests) -> int:
    """The render command. `args`: app.py's parsed `render` options; returns the exit status."""
    if args.frames is not None or args.turntable is not None:
        from renderer.commands.animation.command import run_animation

        return run_animation(args, stop)
    for option, value in (("--fps", args.fps), ("--video", args.video)):
        if value is not None:
            raise ValueError(f"{option} is for animations: add --frames A:B or --turntable SECONDS")
    plan = plan_render(args)
    from renderer.runtime.arch import init_taichi

    # A distributed render's driver only merges films and runs adaptive sampling's checks: the CPU.
    used = init_taichi("cpu" if plan.distributed else plan.arch, optimize=plan.optimize)
    if plan.checkpoints is not None:
        plan.checkpoints.header = replace(plan.checkpoints.header, arch=_arch_name(used))
    if plan.previous is not None:
        for name, value in (("arch", _arch_name(used)), ("optimize", plan.optimize)):
            if value != getattr(plan.previous, name):
                print(f"warning: {name} {value} differs from the checkpoint's {getattr(plan.previous, name)}: the "
                      "result will not be bit-identical to an uninterrupted render", file=sys.stderr)
    begun = (f", continuing at {spp_text(plan.resume.spp_done + plan.resume.slices_in_round / ROUND_SLICES)} spp"
             if plan.resume else "")
    where = used if plan.distributed is None else plan.distributed.where(plan.arch)
    print(f"rendering {plan.scene.name} with {plan.job.integrator} on {where}{begun}", file=sys.stderr)
    if plan.distributed is not None:
        result = _render_distributed(plan, stop)
    else:
        result = render(plan.scene, plan.job, progress=progress_bar(), stop=stop, checkpoints=plan.checkpoints,
                        resume=plan.resume)
    print(file=sys.stderr)
    if result.mean_spp == 0:  # (a share of a sample is an image: pixels a first round reached)
        print("interrupted before the first pass: nothing written", file=sys.stderr)
    else:
        write_outputs(plan, result)
    return stop.exit_code or 0


def plan_render(args) -> RenderPlan:
    """Read and check the options, the scene and the checkpoint to continue (one-line errors)."""
    from renderer.scene.catalog import load_any, resolve_scene
    from renderer.scene.limits import check_film
    from renderer.scene.load_options import options_from_arguments

    for path, check in ((args.out, check_output_path), (args.variance, check_variance_path),
                        (args.checkpoint, check_checkpoint_path)):
        if path is not None:
            check(path)  # the paths given: before reading anything
    previous = read_header(args.resume) if args.resume is not None else None
    if args.scene is None and previous is None:
        raise ValueError("render: give a SCENE, or --resume CHECKPOINT")
    scene = load_any(resolve_scene(args.scene if args.scene is not None else previous.scene),
                     options_from_arguments(args))
    job = job_from_arguments(args, scene, previous)
    check_denoising(job)
    check_film(scene.path, *job.size, scene.model_files.options.budget,
               "--size" if args.size else "the scene's render.width x height", aovs=job.keeps_aovs)
    out = args.out or (Path(previous.out) if previous else DEFAULT_OUT_DIR / f"{scene.name}_{job.integrator}.png")
    variance = args.variance or (Path(previous.variance) if previous and previous.variance else None)
    check_output_path(out)
    if variance is not None:
        check_variance_path(variance)
    arch = args.arch or (previous.arch if previous else "auto")
    choice = choose_for_render(args.optimize, previous.optimize if previous else None, job, scene.geometry, arch)
    optimize = choice.level
    header = _header(scene, job, out, variance, arch, optimize)
    if previous is not None:
        problems = previous.mismatches(header)
        if problems:
            raise SceneError(args.resume, "cannot continue this render: " + "; ".join(problems))
        if job.spp is not None and job.spp < previous.spp_done:
            raise ValueError(f"--spp {job.spp}: the checkpoint {args.resume} already has {previous.spp_done} spp")
    checkpoints = _checkpoint_policy(args, job, out, header, previous)
    aovs = aovs_path(out) if job.aovs and aovs_path(out) != out else None
    raw = raw_path(out) if job.denoise else None
    for beside in (aovs, raw):
        if beside is not None:
            check_writable(beside)
    distinct = [p.resolve() for p in (out, variance, checkpoints.path if checkpoints else None, aovs, raw)
                if p is not None]
    if len(set(distinct)) != len(distinct):
        raise ValueError(f"{out}: --out, --variance, --checkpoint, the AOV file and the raw image must be "
                         "different files")
    resume = None
    if previous is not None:
        _, state = load_checkpoint(args.resume)
        most = int((state.count.astype("int64") + state.rejected).max(initial=0))
        if job.spp is not None and job.spp < most:  # (pixels of a stopped round or a distributed group)
            raise ValueError(f"--spp {job.spp}: pixels of the checkpoint {args.resume} already have {most} samples")
        resume = Resume(state, previous.spp_done, previous.seconds_rendered, previous.slices_in_round)
    distributed = _distributed_plan(args, job, previous)
    if distributed is not None and checkpoints is not None:
        checkpoints.header = replace(checkpoints.header, workers=distributed.workers or 0)
    if choice.automatic:  # (once every check has passed: a refusal stays one line)
        print(choice.line(), file=sys.stderr)
    return RenderPlan(scene, job, out, variance, arch, optimize, checkpoints, resume, previous, distributed)


def _distributed_plan(args, job: RenderJob, previous: CheckpointHeader | None) -> "DistributedOptions | None":
    """Ray workers when asked for, or when continuing a distributed render (its pixel groups may
    stand at different sample counts: only the distributed driver continues that exactly)."""
    workers = getattr(args, "workers", None)
    address = getattr(args, "ray_address", None)
    if workers is None and address is None and previous is not None and previous.workers is not None:
        if not previous.workers:
            raise ValueError(f"{args.resume}: a render on a Ray cluster; continue it with --ray-address ADDR (or "
                             "--workers K on this machine)")
        workers = previous.workers
    if workers is None and address is None:
        return None
    from renderer.integrators import make_integrator

    if hasattr(make_integrator(job.integrator), "make_program"):
        raise ValueError(f"--workers: {job.integrator} renders whole-image photon passes and cannot be distributed; "
                         "use path, nee or mis")
    from renderer.commands.distributed.render import DistributedOptions

    return DistributedOptions(workers, address, getattr(args, "worker_threads", None), getattr(args, "chunk_spp", None))


def _render_distributed(plan: RenderPlan, stop: StopRequests) -> RenderResult:
    from renderer.commands.distributed.render import DistributedRun, progress_line, render_distributed
    from renderer.scene.load_options import LoadOptions

    run = DistributedRun()
    if stop is not None:
        stop.defer()
    result = render_distributed(plan.scene, plan.job, plan.distributed, plan.arch, plan.optimize,
                                plan.scene.model_files.options or LoadOptions(),
                                progress_line(), stop, plan.checkpoints, plan.resume, run)
    lost = f", {run.lost_chunks} chunks re-run after their worker died" if run.lost_chunks else ""
    print(f"\n{run.workers} workers, {run.groups} pixel groups, {run.chunks} chunks{lost}", file=sys.stderr)
    return result


def write_outputs(plan: RenderPlan, result: RenderResult) -> None:
    """The image (its spp and status in its metadata), the variance, the last checkpoint; a line each."""
    from renderer.output.render_outputs import aov_layers, denoised

    metadata = image_metadata(plan.scene, plan.job, result)
    image, raw, denoising = result.image, None, ""
    if plan.job.denoise:
        start = time.perf_counter()
        raw, image = result.image, denoised(result)
        metadata["denoised"] = "Intel Open Image Denoise"
        denoising = f", denoised in {time.perf_counter() - start:.1f} s"
    layers = aov_layers(result, raw) if plan.job.aovs else None
    tonemapper = display_tonemapper(plan.job.integrator, plan.job.tonemapper)
    save(image, plan.out, plan.job.exposure, tonemapper, metadata, layers)
    rejected = f", {result.rejected} non-finite samples dropped" if result.rejected else ""
    stopped = ", interrupted" if result.interrupted else ""
    adaptive = ""
    if result.pixels_active is not None:
        pixels = result.state.count.size
        adaptive = (f", adaptive: {result.pixel_mean_spp:.1f} spp per pixel on average, "
                    f"{100.0 * (pixels - result.pixels_active) / pixels:.0f}% of pixels stopped")
    print(f"{plan.out}  ({result.spp_text()} spp in {result.seconds:.1f} s{adaptive}{rejected}{stopped}{denoising})")
    if raw is not None:
        raw_metadata = {key: value for key, value in metadata.items() if key != "denoised"}
        save(raw, raw_path(plan.out), plan.job.exposure, tonemapper,
             {**raw_metadata, "content": "the raw render, before denoising"})
        print(f"{raw_path(plan.out)}  (the raw render, before denoising)")
    if layers and aovs_path(plan.out) != plan.out:
        print(f"{aovs_path(plan.out)}  (AOVs: {', '.join(layers)})")
    if plan.variance is not None:
        save_variance(result, plan.variance, metadata)
        print(f"{plan.variance}  (variance of each pixel's mean)")
    if plan.checkpoints is not None:
        written = plan.checkpoints.finish(result)
        if written:
            print(written)


def check_checkpoint_path(path: Path, automatic: bool = False) -> None:
    """A checkpoint may have any name (as --out may), but replaces only a checkpoint: a slip of the
    keyboard (--checkpoint a.png for --out a.png) must not replace an image."""
    check_writable(path)
    if path.exists() and not is_checkpoint(path):
        remedy = ("the automatic checkpoint beside --out would replace it (move it away, or give "
                  "--checkpoint FILE)" if automatic else "refusing to replace it with a checkpoint "
                  "(choose another file, or remove it)")
        raise ValueError(f"{path}: exists and is not a Lantern checkpoint; {remedy}")


def _header(scene, job: RenderJob, out: Path, variance: Path | None, arch: str, optimize: str) -> CheckpointHeader:
    width, height = job.size
    return CheckpointHeader(
        lantern_version=lantern_version(), scene=str(Path(scene.path).resolve()), scene_hash=scene_fingerprint(scene),
        width=width, height=height, integrator=job.integrator, sampler=scene.render.sampler, seed=job.seed,
        max_depth=job.max_depth, spp_done=0, slices_in_round=0, spp_target=job.spp, seconds_budget=job.seconds, seconds_rendered=0.0,
        arch=arch, optimize=optimize, out=str(out.resolve()), variance=str(variance.resolve()) if variance else None,
        exposure=job.exposure, tonemapper=job.tonemapper, automatic=False, denoise=job.denoise, aovs=job.aovs,
        noise_threshold=job.noise_threshold, min_spp=job.min_spp, packets=job.packets)


def _checkpoint_policy(args, job: RenderJob, out: Path, header: CheckpointHeader,
                       previous: CheckpointHeader | None) -> CheckpointPolicy | None:
    from renderer.integrators import make_integrator

    explicit = args.checkpoint is not None or previous is not None
    # An integrator with programs of its own (sppm) keeps device state beyond the film.
    if hasattr(make_integrator(job.integrator), "make_program"):
        if explicit:
            raise ValueError(f"{args.checkpoint or args.resume}: {job.integrator} renders cannot be checkpointed "
                             "(its photon statistics live outside the film)")
        return None
    if args.checkpoint is not None:
        return CheckpointPolicy(args.checkpoint, args.checkpoint_every, header, active=True)
    if previous is not None:  # the checkpoint continued is kept up to date (and stays automatic or not)
        check_writable(args.resume)
        return CheckpointPolicy(args.resume, args.checkpoint_every, replace(header, automatic=previous.automatic),
                                active=True)
    path = out.with_name(out.name + CHECKPOINT_EXTENSION)
    check_checkpoint_path(path, automatic=True)  # beside --out, which has just been checked
    return CheckpointPolicy(path, args.checkpoint_every, replace(header, automatic=True), active=False)


def _arch_name(used: str) -> str:
    """Taichi's name of the back-end in use as an --arch choice."""
    return "cpu" if used in CPU_ARCHES else used

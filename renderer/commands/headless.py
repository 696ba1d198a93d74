"""Headless rendering to a file, with a progress bar: the render loop of `app.py render`.

Passes are short (about CHUNK_SECONDS each; a pass may be a share of a sample per pixel, a run of
the pixel slices of renderer/film/pixel_slices.py), so a stop request, a checkpoint or a --time budget
is honoured within about that long even where one sample of the image takes longer. Continuing
from a checkpoint restores the film's exact float32 state, whose per-pixel counts are the pixels'
sample indices, and the position in the round of slices, so the image is the one an
uninterrupted render gives, bit for bit.
"""
from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Protocol

import numpy as np
import taichi as ti

from renderer.film.adaptive import DEFAULT_MIN_SPP
from renderer.camera import CameraFrame
from renderer.film.accumulation import Film, FilmState
from renderer.output.atomic_write import creation_problem
from renderer.output.image_io import write_exr, write_png
from renderer.integrators import make_integrator
from renderer.film.pixel_slices import ROUND_SLICES, spp_text
from renderer.renderer import AdaptiveSettings, MeshOptions, Renderer
from renderer.scene.description import Scene
from renderer.output.tonemap import tonemap_array
from renderer.runtime.version import lantern_version

OUTPUT_EXTENSIONS = (".png", ".exr")
# Aim each pass at about this long: long enough to amortise launch overhead, short enough for a
# live progress bar, a prompt stop on Ctrl-C and a --time overshoot of at most this.
CHUNK_SECONDS = 0.5
# A pass grows at most this much over the last: a single fast measurement cannot make it long.
CHUNK_GROWTH = 4
# Sample indices are 32-bit signed counts: a render stops at this many samples per pixel.
MAX_SPP = 2**31 - 1
# A pass at least this long measures the rendering rate that estimates a render's length: each
# pass also costs a launch and a sync (about half a millisecond on the CPU), which is under 1% of
# it. A shorter pass overstates the time per slice: the one-slice second pass of a 16x16 image at
# 4000 spp estimated 442 s for a render of 1.2 s.
RATE_PASS_SECONDS = 0.1


@dataclass
class RenderJob:
    spp: int | None = None
    seconds: float | None = None
    size: tuple[int, int] | None = None
    integrator: str | None = None
    max_depth: int | None = None
    seed: int | None = None
    exposure: float = 0.0
    tonemapper: str | None = None
    denoise: bool = False  # the image written is denoised (renderer/output/denoise.py)
    aovs: bool = False  # albedo, normal, variance, raw colour and spp written with it
    noise_threshold: float | None = None  # adaptive sampling (renderer/film/adaptive.py); None: uniform
    min_spp: int = DEFAULT_MIN_SPP
    packets: int = 0  # rays a packet on the CPU (renderer/packets/); 0: one ray at a time

    @property
    def keeps_aovs(self) -> bool:
        return self.denoise or self.aovs

    def resolved(self, scene: Scene) -> "RenderJob":
        """The job with the scene's settings where it names none (except a budget: spp or time)."""
        settings = scene.render
        return replace(self, size=self.size or settings.image_size,
                       integrator=self.integrator or settings.integrator,
                       max_depth=settings.max_depth if self.max_depth is None else self.max_depth,
                       seed=settings.seed if self.seed is None else self.seed,
                       spp=self.spp if self.spp is not None or self.seconds is not None else settings.spp)


@dataclass
class Resume:
    """Where a checkpointed render stopped."""

    state: FilmState
    spp_done: int
    seconds_rendered: float
    slices_in_round: int = 0  # pixel slices of the round after spp_done already rendered


class FilmSource(Protocol):
    """What a checkpoint is taken from: the Renderer (its film with the AOVs)."""

    def state(self) -> FilmState: ...


class Checkpoints(Protocol):
    """What the render loop tells the checkpoint policy (renderer/commands/render.py) after a pass."""

    def after_pass(self, film: FilmSource, spp_done: int, seconds_rendered: float, expected_seconds: float | None,
                   slices_in_round: int = 0) -> None:
        """`expected_seconds`: the render's whole rendering time as now estimated; None while no
        pass has measured the rate."""


@dataclass
class RenderResult:
    image: np.ndarray  # linear (H, W, 3)
    spp: int  # samples every pixel has
    seconds: float  # wall time of this run, compilation included
    rejected: int
    integrator: str
    # per pixel and channel, the variance of the mean (s^2 / n; +inf where unknown: fewer than 2
    # samples, or an integrator whose image is not a mean of independent samples, such as sppm)
    variance: np.ndarray | None = None
    interrupted: bool = False  # stopped by a request before its budget was spent
    seconds_rendered: float = 0.0  # rendering time the --time budget counts, over every run
    film: Film | None = None  # the film
    slices_in_round: int = 0  # of a round begun but not finished (an interruption): some pixels have spp + 1
    state: FilmState | None = None  # the film's arrays: counts, adaptive state, AOVs (Renderer.state())
    pixels_active: int | None = None  # with adaptive sampling: pixels it had not stopped
    renderer: FilmSource | None = None  # the renderer, for a final checkpoint (film and AOVs)

    @property
    def mean_spp(self) -> float:
        return self.spp + self.slices_in_round / ROUND_SLICES

    @property
    def pixel_mean_spp(self) -> float:
        """Samples per pixel on average over the image (below mean_spp where adaptive sampling
        stopped pixels)."""
        if self.state is None:
            return self.mean_spp
        return float(np.mean(self.state.count + self.state.rejected))

    def spp_text(self) -> str:
        """'64', or '12.25' for a render stopped within a round of pixel slices."""
        return spp_text(self.mean_spp)


def check_writable(path: Path) -> None:
    """Raise ValueError("<path>: <problem>") unless a file can be written at `path`: it is not a
    directory, and its directory exists or can be created, and lets us create files: the
    temporary file the atomic write makes beside it is created and removed (with any folders
    made for it), so a render never ends in a failed write."""
    if path.is_dir():
        raise ValueError(f"{path}: is a directory")
    existing = path.parent
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise ValueError(f"{path}: cannot create its directory ({existing} is not a directory)")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise ValueError(f"{path}: cannot write in {existing} (permission denied)")
    problem = creation_problem(path)
    if problem:
        raise ValueError(f"{path}: {problem}")


def check_output_path(out: Path) -> None:
    if out.suffix.lower() not in OUTPUT_EXTENSIONS:
        raise ValueError(f"{out}: unsupported output extension '{out.suffix}' (use .png or .exr)")
    check_writable(out)


def check_variance_path(out: Path) -> None:
    if out.suffix.lower() != ".exr":
        raise ValueError(f"{out}: unsupported variance extension '{out.suffix}' (the variance is linear "
                         "float data: use .exr)")
    check_writable(out)


def render(scene: Scene, job: RenderJob, progress=None, stop=None, checkpoints: Checkpoints | None = None,
           resume: Resume | None = None, renderer: Renderer | None = None,
           camera: CameraFrame | None = None) -> RenderResult:
    """Render `job` (resolved against the scene). `stop`: a StopRequests (renderer/commands/interrupts.py),
    asked at every pass boundary; `checkpoints`: told after every pass; `resume`: continue there.
    `renderer`: one made for this scene and job's size, reused with its film cleared (an
    animation's frames compile once); `camera`: instead of the scene's."""
    job = job.resolved(scene)
    width, height = job.size
    integrator = job.integrator
    make_integrator(integrator)  # a clear error before any compilation
    target_spp = job.spp
    if renderer is None:
        renderer = Renderer(scene, (width, height), MeshOptions(packets=job.packets), aovs=job.keeps_aovs)
    else:
        renderer.reset(width, height)
    if job.noise_threshold is not None:
        renderer.set_adaptive(AdaptiveSettings(job.noise_threshold, job.min_spp))
    seconds_before = 0.0
    if resume is not None:
        renderer.restore(resume.state, resume.spp_done * ROUND_SLICES + resume.slices_in_round)
        seconds_before = resume.seconds_rendered
    camera = camera if camera is not None else CameraFrame.from_spec(scene.camera)
    if job.packets:
        print(renderer.packet_status(integrator, renderer.features(camera), scene.render.sampler), file=sys.stderr)
    if stop is not None:
        stop.defer()  # from here on there is an image to save: a signal stops at the next pass
    start = time.perf_counter()
    budget_start = None  # a --time budget counts rendering only, from the end of the first pass
    seconds_per_slice = None  # measured on passes after the first (which includes compilation)
    measured_per_slice = None  # the same, of the last pass of at least RATE_PASS_SECONDS
    n = 1
    interrupted = False
    target = None if target_spp is None else target_spp * ROUND_SLICES
    limit = MAX_SPP * ROUND_SLICES

    def rendered() -> float:
        return seconds_before + (time.perf_counter() - budget_start if budget_start is not None else 0.0)

    while True:
        done = renderer.slices_done
        if target is not None and done >= target:
            break
        if target is None and (rendered() >= job.seconds or done >= limit):
            break
        if renderer.pixels_active == 0:  # adaptive sampling stopped every pixel
            break
        if stop is not None and stop.requested:  # (a request during the last pass stops nothing)
            interrupted = True
            break
        n = pass_slices(seconds_per_slice, n, (target or limit) - done,
                        None if target is not None else job.seconds - rendered())
        t0 = time.perf_counter()
        renderer.render_slices(camera, n, integrator, job.max_depth, job.seed)
        # GPU back-ends launch asynchronously: without waiting, a pass would seem to take only
        # its launch, and the next pass (sized by that rate), the progress line, the time budget
        # and the checkpoints' timing would all be wrong (a no-op on the CPU).
        ti.sync()
        elapsed = time.perf_counter() - t0
        n = renderer.slices_done - done  # (an integrator with whole-image passes rounds up to a sample)
        if budget_start is None:
            budget_start = time.perf_counter()
        else:
            seconds_per_slice = elapsed / n
            if elapsed >= RATE_PASS_SECONDS:
                measured_per_slice = seconds_per_slice
        if checkpoints is not None and seconds_per_slice is not None:
            expected = job.seconds  # a time budget; an spp target: once a pass has measured the rate
            if target is not None:
                expected = (None if measured_per_slice is None
                            else rendered() + (target - renderer.slices_done) * measured_per_slice)
            checkpoints.after_pass(renderer, renderer.samples_done, rendered(), expected,
                                   renderer.slices_done % ROUND_SLICES)
        if progress and seconds_per_slice is not None:  # the compiling pass says nothing of the rate
            progress(renderer.mean_spp, target_spp, rendered(), width * height, job.seconds)
    total = time.perf_counter() - start
    # A render stopped within its first round shows the pixels not reached yet as the viewer does
    # (the nearest sampled grid point); their variance stays +inf. A complete render: the mean.
    return RenderResult(renderer.shown_image(), renderer.samples_done, total, renderer.film.stats()["rejected"], integrator,
                        renderer.film.variance_of_mean_image(), interrupted, rendered(), renderer.film,
                        renderer.slices_done % ROUND_SLICES, renderer.state(),
                        renderer.pixels_active if job.noise_threshold is not None else None, renderer)


def pass_slices(seconds_per_slice: float | None, previous: int, slices_left: int, seconds_left: float | None) -> int:
    """Pixel slices of the next pass (ROUND_SLICES make a sample per pixel): about CHUNK_SECONDS of
    work at the measured rate, at most CHUNK_GROWTH times the previous pass, never past the spp
    target or the time budget. The first pass, which compiles, is a single slice: its time says
    nothing of the rate, and a huge or slow image must not make the user wait for a whole sample."""
    if seconds_per_slice is None:
        return 1
    rate = max(seconds_per_slice, 1e-12)
    n = min(previous * CHUNK_GROWTH, int(CHUNK_SECONDS / rate))
    if seconds_left is not None:
        n = min(n, math.ceil(max(seconds_left, 0.0) / rate))
    return max(1, min(n, slices_left))


def image_metadata(scene: Scene, job: RenderJob, result: RenderResult) -> dict[str, str]:
    """What the image files say about how they were made (PNG text chunks, EXR attributes)."""
    job = job.resolved(scene)
    return {"Software": f"Lantern {lantern_version()}", "scene": scene.name, "integrator": result.integrator,
            "spp": result.spp_text(), "seed": str(job.seed), "max_depth": str(job.max_depth),
            "status": "interrupted" if result.interrupted else "complete"}


def save(image: np.ndarray, out: Path, exposure: float = 0.0, tonemapper: str = "aces",
         metadata: dict[str, str] | None = None, layers: dict[str, np.ndarray] | None = None) -> None:
    """A linear image to `out`: an EXR as is (with `layers`, renderer/output/render_outputs.py), a PNG
    tone-mapped (its layers then go to an EXR beside it)."""
    if out.suffix.lower() == ".exr":
        write_exr(out, image, metadata, layers)
    else:
        write_png(out, tonemap_array(image, exposure, tonemapper), metadata)
        if layers:
            from renderer.output.render_outputs import aovs_path

            layers = dict(layers)
            raw = layers.pop("raw", image)
            write_exr(aovs_path(out), raw, {**(metadata or {}), "content": "render AOVs"}, layers)


def save_variance(result: RenderResult, out: Path, metadata: dict[str, str] | None = None) -> None:
    """The variance of each pixel's mean (linear EXR, per channel): with the mean image, what a z-test
    of the render against a reference needs, z = (mean - reference) / sqrt(variance + reference's)."""
    write_exr(out, result.variance, {**(metadata or {}), "content": "variance of each pixel's mean"})


def display_tonemapper(integrator: str, requested: str | None) -> str:
    """Debug views ask for their own mapping unless the user names one."""
    return requested or make_integrator(integrator).display_tonemapper or "aces"


def progress_head(spp: float, target: int | None, elapsed: float, seconds: float | None) -> tuple[str, float]:
    """'[####      ] 12/64 spp' of a render towards an spp target or a time budget, and its ETA in seconds."""
    if target:
        frac = spp / target
        eta = elapsed * (1 - frac) / max(frac, 1e-9)
    else:
        frac = min(1.0, elapsed / seconds)
        eta = max(0.0, seconds - elapsed)
    bar = "#" * int(frac * 30)
    total = f"/{target}" if target else ""
    return f"[{bar:<30}] {spp_text(spp)}{total} spp", eta


def progress_bar(stream=sys.stderr):
    def report(spp, target, elapsed, pixels, seconds):
        rate = spp * pixels / max(elapsed, 1e-9)
        head, eta = progress_head(spp, target, elapsed, seconds)
        stream.write(f"\r{head}  {rate / 1e6:6.2f} Msamples/s  ETA {eta:5.1f} s ")
        stream.flush()

    return report

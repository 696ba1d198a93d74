"""Headless rendering to a file, with a progress bar: what `app.py render` runs."""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from renderer.camera import CameraFrame
from renderer.image_io import write_exr, write_png
from renderer.integrators import make_integrator
from renderer.renderer import Renderer
from renderer.scene.model import Scene
from renderer.tonemap import tonemap_array

OUTPUT_EXTENSIONS = (".png", ".exr")
# Aim each kernel launch at about this long: long enough to amortise launch overhead, short
# enough for a live progress bar and a --time budget overshoot of at most this much.
CHUNK_SECONDS = 0.5


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


@dataclass
class RenderResult:
    image: np.ndarray  # linear (H, W, 3)
    spp: int
    seconds: float
    rejected: int
    integrator: str
    # per pixel and channel, the variance of the mean (s^2 / n; +inf where unknown: fewer than 2
    # samples, or an integrator whose image is not a mean of independent samples, such as sppm)
    variance: np.ndarray | None = None


def check_output_path(out: Path) -> None:
    if out.suffix.lower() not in OUTPUT_EXTENSIONS:
        raise ValueError(f"{out}: unsupported output extension '{out.suffix}' (use .png or .exr)")


def check_variance_path(out: Path) -> None:
    if out.suffix.lower() != ".exr":
        raise ValueError(f"{out}: unsupported variance extension '{out.suffix}' (the variance is linear "
                         "float data: use .exr)")


def render(scene: Scene, job: RenderJob, progress=None) -> RenderResult:
    settings = scene.render
    width, height = job.size or (settings.width, settings.height)
    integrator = job.integrator or settings.integrator
    make_integrator(integrator)  # a clear error before any compilation
    target_spp = job.spp if job.spp is not None else (None if job.seconds is not None else settings.spp)
    renderer = Renderer(scene, (width, height))
    camera = CameraFrame.from_spec(scene.camera)
    start = time.perf_counter()
    budget_start = None  # a --time budget counts rendering only, from the end of the first pass
    chunk = 1
    while True:
        done = renderer.samples_done
        if target_spp is not None and done >= target_spp:
            break
        if target_spp is None and budget_start is not None and time.perf_counter() - budget_start >= job.seconds:
            break
        n = chunk if target_spp is None else min(chunk, target_spp - done)
        t0 = time.perf_counter()
        renderer.render(camera, n, integrator, job.max_depth, job.seed)
        elapsed = time.perf_counter() - t0
        if done > 0:  # the first launch includes compilation: do not size chunks from it
            chunk = max(1, min(chunk * 4, int(n * CHUNK_SECONDS / max(elapsed, 1e-6))))
        elif budget_start is None:
            budget_start = time.perf_counter()
        if progress:
            progress(renderer.samples_done, target_spp, time.perf_counter() - (budget_start or start),
                     width * height, job.seconds)
    total = time.perf_counter() - start
    return RenderResult(renderer.image(), renderer.samples_done, total, renderer.film.stats()["rejected"], integrator,
                        renderer.film.variance_of_mean_image())


def save(result: RenderResult, out: Path, exposure: float = 0.0, tonemapper: str = "aces") -> None:
    if out.suffix.lower() == ".exr":
        write_exr(out, result.image)
    else:
        write_png(out, tonemap_array(result.image, exposure, tonemapper))


def save_variance(result: RenderResult, out: Path) -> None:
    """The variance of each pixel's mean (linear EXR, per channel): with the mean image, what a z-test
    of the render against a reference needs, z = (mean - reference) / sqrt(variance + reference's)."""
    write_exr(out, result.variance)


def display_tonemapper(integrator: str, requested: str | None) -> str:
    """Debug views ask for their own mapping unless the user names one."""
    return requested or make_integrator(integrator).display_tonemapper or "aces"


def progress_bar(stream=sys.stderr):
    def report(spp, target, elapsed, pixels, seconds):
        rate = spp * pixels / max(elapsed, 1e-9)
        if target:
            frac = spp / target
            eta = elapsed * (1 - frac) / max(frac, 1e-9)
        else:
            frac = min(1.0, elapsed / seconds)
            eta = max(0.0, seconds - elapsed)
        bar = "#" * int(frac * 30)
        total = f"/{target}" if target else ""
        stream.write(f"\r[{bar:<30}] {spp}{total} spp  {rate / 1e6:6.2f} Msamples/s  ETA {eta:5.1f} s ")
        stream.flush()

    return report

"""Which kernel optimisation level (renderer.runtime.arch.OPTIMIZE_FOR) a `render` uses when --optimize is
not given.

Kernels built with every Taichi IR optimisation ("run") compile several times longer on a cold
offline cache and render SDF scenes a few percent faster (mesh scenes: no difference measured on
the CPU). They repay their compile once the render is long enough: a render taking T seconds with
"compile" kernels takes r T with "run" kernels after C more seconds of compiling, so "run" wins
when T > C / (1 - r), the break-even time. Taichi takes the level at ti.init, before any kernel
exists, so T must come from what is known then:

- a --time budget is T itself (rendering time, after compiling);
- a --spp target gives T >= spp x pixels x a per-sample cost / CPU threads: the cost is the
  cheapest measured for the scene's kind of geometry, halved (a faster CPU), so the estimate
  errs short and "run" is chosen only for renders that are surely long. With adaptive sampling
  only --min-spp samples per pixel are sure. Debug views and SPPM have costs of their own, and a
  GPU's per-sample cost was not measured: their --spp renders keep "compile".

The break-even is taken on a cold cache; with the "run" kernels already cached (a warm start
costs about as much at both levels) the rule leaves a few percent on the table for renders
between a few seconds and the break-even. An explicit --optimize always wins, and a resumed
render keeps its checkpoint's level (bit-identical to the uninterrupted render).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

from renderer.runtime.arch import cpu_expected

# Seconds of rendering (at the "compile" level) after which "run" kernels have repaid their longer
# cold compile, per kind of geometry: C / (1 - r) with a margin. Measured (scripts/optimize_costs.py,
# CPU time): SDF, the showcase, r = 0.94 (median of 10 pairs; mean 0.95, standard error 0.02) and
# C = 52-72 s (median 56 s): about 920 s, doubled. Mesh, the Cornell box and the bunnies, r = 1.00
# (median of 15 pairs; mean 1.02, standard error 0.04) for C = 6-8 s and 84-96 s: no render is
# long enough.
BREAK_EVEN_SECONDS = {"sdf": 1800.0, "mesh": math.inf}
# CPU core-seconds per sample (a camera path) at the "compile" level: the cheapest catalog scene of
# each kind at 320x180, halved (prism 0.93 us, the Cornell box and studio 0.74 us; the showcase
# costs the same per sample at 640x360 as at 320x180).
CORE_SECONDS_PER_SAMPLE = {"sdf": 0.45e-6, "mesh": 0.35e-6}
# Integrators whose per-sample cost the figures above describe (the path tracers).
ESTIMATED_INTEGRATORS = ("path", "nee", "mis")


@dataclass(frozen=True)
class OptimizeChoice:
    level: str  # "compile" or "run"
    reason: str  # why, in a few words
    automatic: bool  # False: given on the command line, or the checkpoint's

    def line(self) -> str:
        """What `render` prints about an automatic choice."""
        return f"kernels optimised for {self.level}: {self.reason}"


@dataclass(frozen=True)
class RenderLength:
    """What is known of a render's length before Taichi starts."""

    seconds: float | None  # a --time budget
    spp: int | None  # the samples per pixel every pixel takes at least (None with a time budget)
    pixels: int
    geometry: str  # "sdf" or "mesh"
    integrator: str
    on_cpu: bool  # the back-end will be the CPU (not known for sure with --arch auto: a CUDA driver may be there)
    cpu_threads: int


def choose_level(given: str | None, resumed: str | None, length: RenderLength) -> OptimizeChoice:
    """The level: `given` (--optimize) if any, else `resumed` (the checkpoint's), else by length."""
    if given is not None:
        return OptimizeChoice(given, "--optimize", automatic=False)
    if resumed is not None:
        return OptimizeChoice(resumed, "the checkpoint's level", automatic=False)
    break_even = BREAK_EVEN_SECONDS[length.geometry]
    if math.isinf(break_even):
        return OptimizeChoice("compile", f"{length.geometry} scenes render no faster with run kernels (measured)",
                              automatic=True)
    repays = f"faster kernels repay their longer compile after about {break_even:.0f} s of rendering"
    if length.seconds is not None:
        level = "run" if length.seconds > break_even else "compile"
        return OptimizeChoice(level, f"--time {length.seconds:g}; {repays}", automatic=True)
    expected = expected_seconds(length)
    if expected is None:
        where = "this integrator" if length.integrator not in ESTIMATED_INTEGRATORS else "a GPU"
        return OptimizeChoice("compile", f"no estimate of the rendering time on {where} (give --time or --optimize)",
                              automatic=True)
    level = "run" if expected > break_even else "compile"
    return OptimizeChoice(level, f"{length.spp} spp expected to take at least ~{expected:.0f} s on "
                                 f"{length.cpu_threads} threads; {repays}", automatic=True)


def expected_seconds(length: RenderLength) -> float | None:
    """A short estimate of the rendering time of a --spp render on the CPU (None: no estimate)."""
    if length.spp is None or not length.on_cpu or length.integrator not in ESTIMATED_INTEGRATORS:
        return None
    return length.spp * length.pixels * CORE_SECONDS_PER_SAMPLE[length.geometry] / max(1, length.cpu_threads)


def choose_for_render(given: str | None, resumed: str | None, job, geometry: str, arch: str) -> OptimizeChoice:
    """choose_level for a resolved RenderJob (renderer/commands/headless.py) on `arch` (an --arch choice)."""
    spp = job.spp
    if spp is not None and job.noise_threshold is not None:
        spp = min(spp, job.min_spp)  # adaptive sampling may stop pixels from there on
    width, height = job.size
    length = RenderLength(job.seconds, spp, width * height, geometry, job.integrator, cpu_expected(arch),
                          len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)
    return choose_level(given, resumed, length)

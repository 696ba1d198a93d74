"""`python app.py bench integrators`: error against time for `path`, `nee` and `mis`, each with the
`independent` and the `sobol` sampler, and Lantern against Mitsuba 3 on the Cornell box.

For every scene (the Cornell box, the bunnies under sky.exr, the studio scene under studio.exr and
the many-lights scene; a scene whose file is missing, or that fails to build, is skipped with a
note), in one process so that ratios are meaningful:

1. Compile: every (integrator, sampler) program is launched once for 1 spp before anything is
   timed; that first launch (compilation, or a load from Taichi's offline cache) is reported
   separately as compile time.
2. Reference: a long `mis` render with the independent sampler, on its own seed (so its noise does
   not correlate with the test images'), for a fixed wall-clock time at a modest size (128x128 for
   the square Cornell box, 160x90 otherwise; smaller with --quick). Its own noise level is reported
   from the film's per-pixel variance of the mean: mean(var) is the MSE that the reference's noise
   adds to any image compared with it (and mean(var / (ref^2 + eps)) the relMSE), so error curves
   flatten towards that floor, and the table also gives the floor-corrected errors (error - floor,
   an unbiased estimate of the error against the true image, since the reference and the test
   image are independent). Under a sun-like map this floor is itself an estimate from a
   heavy-tailed distribution: read it as an order of magnitude there.
3. Error against time: each (integrator, sampler) renders progressively from an empty film on one
   seed (the same seed for all, common random numbers), in launches of 1, 1, 2, 4, ... spp (so the
   totals are powers of two, where Sobol nets are complete), the last launch sized from the
   measured speed to land on the time budget (10 s; 2 s with --quick). After each launch (untimed)
   RMSE, relMSE and relMSE without the 0.1 % worst pixels are computed against the reference.
   Seconds are wall-clock render time (kernel launches up to `ti.sync()`), compile excluded.
   The equal-time table reads every curve at the budget T (log-log interpolation between the two
   launches around T).
4. Mitsuba 3 side by side, on the Cornell box only (the scene file reproduces `mi.cornell_box()`
   value for value; renderer.bench.mitsuba_side renders Mitsuba's with a box filter, as Lantern's
   film does), at the same size and max depth (8): Mitsuba's `path` integrator (which, like
   Lantern's `mis`, combines light and BSDF sampling) on its LLVM variant limited to 2 threads,
   against a Mitsuba reference (its spp and noise floor, estimated from the spread of its
   independent passes, are reported). At equal spp (`mitsuba_target_spp`), Mitsuba and Lantern's
   `path`, `nee` and `mis` (independent sampler, like Mitsuba's) render in turn, round-robin, on
   `mitsuba_target_renders` seeds each (JIT and kernel compilation warmed up first): the median
   time gives samples/s, the images each one's expected error at that spp (RMSE = the root of the
   mean squared error over the seeds, since a few pixels on the light's edge, whose footprint
   straddles an emitter 20 times brighter than the ceiling, weigh a lot in one image's RMSE; the
   same for relMSE, which weighs those pixels down, as a second view). The target is Mitsuba's
   error; the spp each integrator needs to reach it follows from MSE ~ 1/spp (independent
   samples, unbiased), its time from its seconds per spp. The Sobol rows, whose error does not
   fall as 1/spp, read the spp off their step-3 curves against the same Mitsuba reference (log-log
   interpolation; past the curve extrapolated, and marked so) at their curves' own speed. The best
   samplers (Lantern's mis/sobol and nee/sobol, Mitsuba's multijitter: SEEDED_ROWS) are measured
   again over seeds, since one curve is one image at each spp and its RMSE moves by ~10% from seed
   to seed (the light's edge again): at the powers of two around where their curves reach the
   targets (`seeded_levels`), each renders `seeded_renders` seeds in turn, and the spp to each
   target is read off the root of the mean squared error (the mean relMSE) per level, log-log
   between levels; their time per spp is the median of those renders at the top level (taken in
   turn with Mitsuba's, like the independent rows', where a curve and Mitsuba's long render ran
   seconds apart and the machine's speed drifts by 10% over such spans).
   Target: Lantern's `mis` reaches Mitsuba's RMSE no later than Mitsuba does (PASS/FAIL).
   Without Mitsuba (not installed, or no usable variant) the column is skipped with a note.
5. Whole process against Mitsuba (renderer/bench/whole_process.py): Lantern's `render` command and
   a Mitsuba process on the Cornell box at 256x256, 256 spp, max depth 8, timed from start to exit,
   alternating, 3 runs each after a warm-up run each (caches filled), both images read against a
   Mitsuba reference of 1,024 spp at that size. Target: Lantern at most 1.5x Mitsuba's time.
6. A mesh-heavy scene against Mitsuba (renderer/bench/mesh_heavy.py): the stress scene's million
   triangles, each renderer at equal error against its own reference, best sampler against best.

Writes <out_dir>/bench_integrators.json and PNG plots (error against seconds, log-log, one line per
integrator x sampler, per scene; and Lantern against Mitsuba), and prints tables. The '-floor'
columns are clipped at 0 (the floor is an estimate too; a Sobol image can land below it).

Run time, measured here on 2 cores: the full run ~11 minutes once Taichi's offline cache holds the
programs (~1 s each), ~16 minutes cold (the light-sampling programs of the environment-lit and
many-light scenes compile in 20-45 s each; any edit to the integrators, lights or materials makes
them cold again); --quick ~3 minutes warm.
"""
from __future__ import annotations

import math
import time
import traceback
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from renderer.bench.common import (
    REL_MSE_EPS,
    describe_error,
    image_errors,
    load_average,
    load_named_scene,
    log,
    print_table,
    pyplot,
    rel_mse,
    report_header,
    rmse,
    save_figure,
    speed_runtime,
    time_interleaved,
    verdict,
    write_json,
)

INTEGRATORS = ("path", "nee", "mis")
SAMPLERS = ("independent", "sobol")
REFERENCE_INTEGRATOR = "mis"
REFERENCE_SAMPLER = "independent"
SCENES = ("cornell_box", "bunnies", "studio", "many_lights")
MITSUBA_SCENE = "cornell_box"
MITSUBA_LD_SAMPLER = "multijitter"  # Mitsuba's best at equal time here (vs stratified, ldsampler, orthogonal)
# Rows whose spp to the targets is measured over seeds (the best samplers; see step 4)
SEEDED_ROWS = ("mis/sobol", "nee/sobol", f"mitsuba/{MITSUBA_LD_SAMPLER}")
FIREFLY_TRIM = 1e-3  # fraction of pixels with the largest error left out of relMSE*
METRICS = ("rmse", "rel_mse", "rel_mse_trimmed")


@dataclass(frozen=True)
class IntegratorBenchConfig:
    square_size: tuple[int, int] = (128, 128)  # scenes with a square image (the Cornell box)
    wide_size: tuple[int, int] = (160, 90)  # every other scene
    budget_s: float = 10.0  # render time per (integrator, sampler) curve: the equal-time budget
    reference_s: float = 60.0  # render time of each scene's reference
    reference_launch_s: float = 3.0  # longest single launch while rendering the reference
    max_spp: int = 1 << 16  # curves stop here even within the budget
    seed: int = 1  # test images (one seed for every integrator and sampler)
    reference_seed: int = 104729  # reference: independent of the test seed
    scenes: tuple[str, ...] = SCENES
    integrators: tuple[str, ...] = INTEGRATORS
    samplers: tuple[str, ...] = SAMPLERS
    mitsuba: bool = True
    mitsuba_threads: int = 2
    mitsuba_reference_spp: int = 2048  # rendered in passes of mitsuba_pass_spp (memory: one lane per sample)
    mitsuba_pass_spp: int = 256
    mitsuba_target_spp: int = 64  # the target RMSE is Mitsuba's at this spp
    mitsuba_curve_max_spp: int = 512  # Mitsuba's error curve: 1, 2, 4, ... spp, each a separate render
    mitsuba_target_renders: int = 8  # round-robin runs (seeds) of the equal-spp comparison
    seeded_renders: int = 16  # seeds per spp level of the best samplers' error (SEEDED_ROWS)
    seeded_max_spp: int = 128  # highest spp level of that measurement
    # Whole-process time (renderer/bench/whole_process.py): both commands, start to exit
    whole_process: bool = True
    whole_process_size: int = 256
    whole_process_spp: int = 256
    whole_process_runs: int = 3
    whole_process_reference_spp: int = 1024
    # The mesh-heavy comparison with Mitsuba (renderer/bench/mesh_heavy.py): "full", "quick" or "off"
    mesh_heavy: str = "full"


FULL = IntegratorBenchConfig()
QUICK = IntegratorBenchConfig(square_size=(64, 64), wide_size=(96, 54), budget_s=2.0, reference_s=8.0,
                              reference_launch_s=2.0, mitsuba_reference_spp=1024, mitsuba_pass_spp=256,
                              mitsuba_target_spp=32, mitsuba_curve_max_spp=256, mitsuba_target_renders=8,
                              seeded_renders=6, seeded_max_spp=64,
                              whole_process_size=64, whole_process_spp=64, whole_process_runs=2,
                              whole_process_reference_spp=512, mesh_heavy="quick")

def _sync() -> None:
    import taichi as ti

    ti.sync()


def combo(integrator: str, sampler: str) -> str:
    return f"{integrator}/{sampler}"


# --- measurement -----------------------------------------------------------------------------------

def noise_floor(mean: np.ndarray, var_of_mean: np.ndarray) -> dict:
    """The expected MSE / relMSE that an image's own noise adds to any comparison with it."""
    mean = np.asarray(mean, np.float64)
    var = np.asarray(var_of_mean, np.float64)
    var = np.where(np.isfinite(var), var, 0.0)
    mse = float(var.mean())
    return {"mse": mse, "rmse": math.sqrt(mse), "rel_mse": float((var / (mean * mean + REL_MSE_EPS)).mean())}


def progressive(renderer, camera, integrator: str, sampler: str, seed: int, budget_s: float, max_spp: int,
                observe=None, max_launch_s: float | None = None) -> dict:
    """Render from an empty film until `budget_s` seconds of render time (or `max_spp`).

    Launches of 1, 1, 2, 4, ... spp (totals 1, 2, 4, 8, ...), the last one sized from the speed of
    the previous launch to end near the budget; with `max_launch_s`, no launch is planned longer
    than that. After each launch, untimed, `observe(image)` may return a dict of measurements.
    Returns {"points": [{"spp", "seconds", ...}], "spp", "seconds"}.
    """
    renderer.reset()
    points = []
    seconds = 0.0
    done = 0
    n = 1
    while True:
        t0 = time.perf_counter()
        renderer.render(camera, n, integrator, seed=seed, sampler=sampler)
        _sync()
        dt = time.perf_counter() - t0
        seconds += dt
        done += n
        point = {"spp": done, "seconds": seconds}
        if observe is not None:
            point.update(observe(renderer.image()))
        points.append(point)
        if seconds >= budget_s or done >= max_spp:
            break
        per_spp = dt / n
        n = done  # double the total
        if max_launch_s is not None:
            n = min(n, max(1, int(max_launch_s / max(per_spp, 1e-9))))
        remaining = budget_s - seconds
        if per_spp * n > remaining:  # the last launch: end at the budget
            n = max(1, int(math.ceil(remaining / max(per_spp, 1e-9))))
        n = min(n, max_spp - done)
    return {"points": points, "spp": done, "seconds": seconds}


def value_at(points: list[dict], key: str, x_key: str, x: float) -> float:
    """points[key] at x_key = x, interpolated linearly in log-log between the points around x
    (the first point's value when x is before it; the last one's when x is after it)."""
    xs = [p[x_key] for p in points]
    if x <= xs[0]:
        return float(points[0][key])
    for a, b in zip(points, points[1:]):
        if a[x_key] <= x <= b[x_key]:
            ya, yb = a[key], b[key]
            if ya <= 0 or yb <= 0 or b[x_key] == a[x_key]:
                return float(yb)
            t = math.log(x / a[x_key]) / math.log(b[x_key] / a[x_key])
            return float(math.exp(math.log(ya) + t * (math.log(yb) - math.log(ya))))
    return float(points[-1][key])


def spp_to_reach(points: list[dict], key: str, target: float, power: float = 0.5) -> tuple[float, bool]:
    """(spp at which points[key] first falls to `target`, extrapolated?): log-log interpolation
    between the points around it; past the last point, extrapolated with error ~ spp^-power (1/2
    for an RMSE, 1 for an MSE-like metric, of an unbiased estimator), which is then flagged."""
    previous = None
    for p in points:
        if p[key] <= target:
            if previous is None:
                return float(p["spp"]), False
            ya, yb = math.log(previous[key]), math.log(p[key])
            xa, xb = math.log(previous["spp"]), math.log(p["spp"])
            if ya == yb:
                return float(p["spp"]), False
            return float(math.exp(xa + (math.log(target) - ya) * (xb - xa) / (yb - ya))), False
        previous = p
    last = points[-1]
    return float(last["spp"] * (last[key] / target) ** (1.0 / power)), True


def seeded_levels(crossings, cap: int) -> list[int]:
    """The spp levels that bracket where rows reach their targets: powers of two from the largest
    at or below the smallest crossing to the smallest at or above the largest, at most `cap`."""
    finite = [c for c in crossings if math.isfinite(c) and c > 0]
    if not finite:
        return []
    low = max(0, math.floor(math.log2(min(finite))))
    high = min(max(low + 1, math.ceil(math.log2(max(finite)))), int(math.log2(cap)))
    return [1 << k for k in range(low, high + 1)]


def seeded_points(renders: dict, levels, seeds, reference: np.ndarray) -> dict:
    """{name: [{"spp", "rmse", "rel_mse", "renders", "seconds"} per level]}: each `render(spp,
    seed)` returns (image, or a function that reads it back untimed; samples per pixel it took);
    the names render in turn at every level and seed, so a drift of the machine's speed hits all
    alike. RMSE is the root of the mean squared error over the seeds (the expected error at that
    spp), relMSE the mean relMSE, seconds the median wall time of a render (the call, image
    read-back excluded)."""
    ref = np.asarray(reference, np.float64)
    out = {name: [] for name in renders}
    for spp in levels:
        errors = {name: {"spp": spp, "mse": [], "rel_mse": [], "seconds": []} for name in renders}
        for seed in seeds:
            for name, render in renders.items():
                t0 = time.perf_counter()
                image, taken = render(spp, seed)
                errors[name]["seconds"].append(time.perf_counter() - t0)
                image = image() if callable(image) else image
                diff = np.asarray(image, np.float64) - ref
                errors[name]["spp"] = taken
                errors[name]["mse"].append(float((diff * diff).mean()))
                errors[name]["rel_mse"].append(rel_mse(image, ref))
        for name, e in errors.items():
            out[name].append({"spp": e["spp"], "rmse": math.sqrt(float(np.mean(e["mse"]))),
                              "rel_mse": float(np.mean(e["rel_mse"])), "renders": len(e["mse"]),
                              "seconds": float(np.median(e["seconds"]))})
    return out


def convergence(renderer, camera, integrator: str, sampler: str, references: dict, config: IntegratorBenchConfig,
                budget_s: float | None = None) -> dict:
    """One error-against-time curve of (integrator, sampler) against each named reference image.

    references: {name: image}; the first is the main reference (its metrics are stored without a
    prefix), the others' RMSE as "rmse_<name>". Returns the curve, its points at the budget, and
    the final spp and seconds.
    """
    names = list(references)
    main = references[names[0]]

    def observe(image):
        out = image_errors(image, main, FIREFLY_TRIM)
        for name in names[1:]:
            out[f"rmse_{name}"] = rmse(image, references[name])
            out[f"rel_mse_{name}"] = rel_mse(image, references[name])
        return out

    budget = config.budget_s if budget_s is None else budget_s
    run = progressive(renderer, camera, integrator, sampler, config.seed, budget, config.max_spp, observe)
    points = run["points"]
    at_budget = {key: value_at(points, key, "seconds", budget) for key in points[-1] if key not in ("spp", "seconds")}
    at_budget["spp"] = value_at(points, "spp", "seconds", budget)
    rejected = int(renderer.film.rejected_counts().sum())
    return {"integrator": integrator, "sampler": sampler, "curve": points, "spp": run["spp"], "seconds": run["seconds"],
            "samples_per_s": run["spp"] * renderer.film.width * renderer.film.height / run["seconds"],
            "at_budget": at_budget, "rejected_samples": rejected}


class SceneBench:
    """One scene's Renderer at the benchmark size, its camera and compile times."""

    def __init__(self, scene, size: tuple[int, int]):
        from renderer.camera import CameraFrame
        from renderer.renderer import Renderer

        self.scene = scene
        t0 = time.perf_counter()
        self.renderer = Renderer(scene, size)
        self.build_s = time.perf_counter() - t0
        self.camera = CameraFrame.from_spec(scene.camera)
        self.compile_s: dict[str, float] = {}

    @property
    def pixels(self) -> int:
        return self.renderer.film.width * self.renderer.film.height

    def compile(self, integrator: str, sampler: str) -> float:
        """First launch of the program (compiles it, or loads it from the offline cache): 1 spp."""
        key = combo(integrator, sampler)
        if key not in self.compile_s:
            self.renderer.reset()
            t0 = time.perf_counter()
            self.renderer.render(self.camera, 1, integrator, sampler=sampler, seed=0)
            _sync()
            self.compile_s[key] = time.perf_counter() - t0
        return self.compile_s[key]

    def reference(self, config: IntegratorBenchConfig) -> dict:
        """The long `mis` render: image, spp, seconds and its own noise floor."""
        run = progressive(self.renderer, self.camera, REFERENCE_INTEGRATOR, REFERENCE_SAMPLER, config.reference_seed,
                          config.reference_s, 1 << 24, max_launch_s=config.reference_launch_s)
        image = self.renderer.image()
        floor = noise_floor(image, self.renderer.film.variance_of_mean_image())
        return {"image": image, "integrator": REFERENCE_INTEGRATOR, "sampler": REFERENCE_SAMPLER,
                "seed": config.reference_seed, "spp": run["spp"], "seconds": run["seconds"], "noise_floor": floor,
                "rejected_samples": int(self.renderer.film.rejected_counts().sum())}


def scene_size(scene, config: IntegratorBenchConfig) -> tuple[int, int]:
    return config.square_size if scene.render.width == scene.render.height else config.wide_size


def bench_scene(scene, config: IntegratorBenchConfig, extra_references: dict | None = None) -> dict:
    """Compile, reference and the error curves of every (integrator, sampler) for one scene."""
    size = scene_size(scene, config)
    bench = SceneBench(scene, size)
    result = {"scene": scene.name, "size": list(size), "max_depth": scene.render.max_depth, "build_s": bench.build_s,
              "errors": {}}
    combos = [(i, s) for i in config.integrators for s in config.samplers]
    if (REFERENCE_INTEGRATOR, REFERENCE_SAMPLER) not in combos:
        combos.insert(0, (REFERENCE_INTEGRATOR, REFERENCE_SAMPLER))
    log(f"[{scene.name}] {size[0]}x{size[1]}: compiling {len(combos)} programs ...")
    for integrator, sampler in combos:
        try:
            seconds = bench.compile(integrator, sampler)
            log(f"[{scene.name}]   {combo(integrator, sampler)}: {seconds:.1f} s")
        except Exception as error:  # noqa: BLE001 - one broken program must not end the benchmark
            result["errors"][combo(integrator, sampler)] = describe_error(error)
            log(f"[{scene.name}]   {combo(integrator, sampler)} FAILED: {describe_error(error)}")
    result["compile_s"] = dict(bench.compile_s)
    failed = result["errors"].get(combo(REFERENCE_INTEGRATOR, REFERENCE_SAMPLER))
    if failed:
        result["skipped"] = f"the reference integrator failed: {failed}"
        return result

    log(f"[{scene.name}] reference: {REFERENCE_INTEGRATOR} for {config.reference_s:g} s ...")
    reference = bench.reference(config)
    result["reference"] = {k: v for k, v in reference.items() if k != "image"}
    log(f"[{scene.name}]   {reference['spp']} spp in {reference['seconds']:.1f} s, noise floor RMSE "
        f"{reference['noise_floor']['rmse']:.3g}, relMSE {reference['noise_floor']['rel_mse']:.3g}")
    references = {"reference": reference["image"], **(extra_references or {})}
    curves = []
    for integrator in config.integrators:
        for sampler in config.samplers:
            if combo(integrator, sampler) in result["errors"]:
                continue
            log(f"[{scene.name}] {combo(integrator, sampler)}: {config.budget_s:g} s ...")
            try:
                curves.append(convergence(bench.renderer, bench.camera, integrator, sampler, references, config))
            except Exception as error:  # noqa: BLE001
                result["errors"][combo(integrator, sampler)] = describe_error(error)
    floor = reference["noise_floor"]
    for c in curves:
        b = c["at_budget"]
        c["at_budget_floor_corrected"] = {
            "rmse": math.sqrt(max(b["rmse"] ** 2 - floor["mse"], 0.0)),
            "rel_mse": max(b["rel_mse"] - floor["rel_mse"], 0.0)}
    result["curves"] = curves
    result["renderer"] = bench  # kept for the Mitsuba comparison; removed before writing JSON
    return result


# --- Mitsuba ------------------------------------------------------------------------------------

def light_edge_mask(reference: np.ndarray, threshold: float = 2.0) -> np.ndarray:
    """(H, W) bool: pixels within one pixel of the boundary between directly seen emitters
    (max channel > threshold; the Cornell box's light is ~18, its brightest wall < 1) and the rest."""
    light = np.asarray(reference).max(axis=-1) > threshold
    padded = np.pad(light, 1, mode="edge")
    h, w = light.shape
    windows = [padded[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)]
    return np.logical_or.reduce(windows) & ~np.logical_and.reduce(windows)


def mitsuba_reference(config: IntegratorBenchConfig, size: tuple[int, int], max_depth: int) -> dict:
    """Mitsuba's reference image (mean of independent passes) and its noise floor (from the spread
    of the passes: var of the mean = sample variance of the pass images / passes)."""
    from renderer.bench import mitsuba_side as ms

    ms.set_threads(config.mitsuba_threads)
    scene = ms.load_cornell_box(size[0], size[1], max_depth)
    passes = max(2, config.mitsuba_reference_spp // config.mitsuba_pass_spp)
    t0 = time.perf_counter()
    images = [ms.render_scene(scene, config.mitsuba_pass_spp, seed=config.reference_seed + k).astype(np.float64)
              for k in range(passes)]
    seconds = time.perf_counter() - t0
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    var_of_mean = stack.var(axis=0, ddof=1) / passes
    return {"scene": scene, "image": mean.astype(np.float32), "spp": passes * config.mitsuba_pass_spp,
            "passes": passes, "seconds": seconds, "noise_floor": noise_floor(mean, var_of_mean)}


def mitsuba_comparison(cornell: dict, config: IntegratorBenchConfig, mitsuba_ref: dict) -> dict:
    """Samples/s and time to Mitsuba's target RMSE: Mitsuba against Lantern's mis and path."""
    from renderer.bench import mitsuba_side as ms

    bench: SceneBench = cornell["renderer"]
    size = tuple(cornell["size"])
    pixels = size[0] * size[1]
    mscene = mitsuba_ref["scene"]
    ref = mitsuba_ref["image"]
    # Mitsuba's own curve: separate renders at 1, 2, 4, ... spp (a Mitsuba render is not
    # progressive), each on its own seed; JIT kernels are warmed up by the reference passes.
    def mitsuba_curve(scene):
        points = []
        spp = 1
        while spp <= config.mitsuba_curve_max_spp:
            t0 = time.perf_counter()
            image = ms.render_scene(scene, spp, seed=config.seed + spp)
            seconds = time.perf_counter() - t0
            # the samples it took: multijitter rounds some counts up (32 -> 35)
            points.append({"spp": ms.samples_taken(scene), "seconds": seconds, "rmse": rmse(image, ref),
                           "rel_mse": rel_mse(image, ref)})
            spp *= 2
        return points

    curve = mitsuba_curve(mscene)
    # Best against best: Mitsuba with its stratified low-discrepancy sampler (on this scene it
    # converges like Lantern's Sobol sampler), set against Lantern's sobol rows.
    ld_scene = ms.load_cornell_box(size[0], size[1], cornell["max_depth"], sampler=MITSUBA_LD_SAMPLER)
    ms.render_scene(ld_scene, 1, seed=0)  # JIT warm-up for this sampler
    ld_curve = mitsuba_curve(ld_scene)
    # Equal spp, round-robin: Mitsuba and Lantern's independent-sampler integrators each render
    # target_spp on `mitsuba_target_renders` seeds in turn (a slow drift of the machine hits all
    # alike). Times give samples/s (median); images give each one's expected error at target_spp
    # (the mean of the squared errors over the seeds: a handful of pixels on the light's edge weigh
    # a lot in one image's RMSE, so one render alone is a noisy measure).
    target_spp = config.mitsuba_target_spp
    lantern = [name for name in config.integrators if combo(name, "independent") in bench.compile_s]
    seeds = {name: iter(range(config.seed + 7919, config.seed + 7919 + 1000)) for name in ["mitsuba", *lantern]}
    images = {}

    def mitsuba_call():
        images["mitsuba"] = ms.render_scene(mscene, target_spp, seed=next(seeds["mitsuba"]))

    def lantern_call(name):
        def call():
            bench.renderer.reset()
            bench.renderer.render(bench.camera, target_spp, name, seed=next(seeds[name]), sampler="independent")
            _sync()
        return call

    calls = {"mitsuba": mitsuba_call, **{name: lantern_call(name) for name in lantern}}
    edge = light_edge_mask(ref)
    errors = {name: [] for name in calls}

    def measure(name):  # untimed, after each timed run
        image = images["mitsuba"] if name == "mitsuba" else bench.renderer.image()
        squared = (np.asarray(image, np.float64) - ref) ** 2
        errors[name].append({"mse": float(squared.mean()), "rel_mse": rel_mse(image, ref),
                             "edge_share": float(squared[edge].sum() / max(squared.sum(), 1e-30))})

    timings = time_interleaved(calls, runs=config.mitsuba_target_renders, warmup=1, after=measure)
    mse = {name: float(np.mean([e["mse"] for e in errors[name]])) for name in calls}
    rel = {name: float(np.mean([e["rel_mse"] for e in errors[name]])) for name in calls}
    target, target_rel = math.sqrt(mse["mitsuba"]), rel["mitsuba"]
    edge_share = float(np.mean([e["edge_share"] for e in errors["mitsuba"]]))

    rows = {}
    for name in calls:
        per_spp = timings[name].median / target_spp
        # MSE ~ 1/spp for an unbiased estimator with independent samples: the spp at which this
        # one's expected error equals the target
        spp_needed = target_spp * mse[name] / mse["mitsuba"]
        spp_rel = target_spp * rel[name] / rel["mitsuba"]
        rows[name if name == "mitsuba" else combo(name, "independent")] = {
            "spp_per_s": 1.0 / per_spp, "samples_per_s": pixels / per_spp, "timing": timings[name].as_dict(),
            "rmse_at_target_spp": math.sqrt(mse[name]), "rel_mse_at_target_spp": rel[name], "measured": "seeds",
            "spp_to_target": spp_needed, "extrapolated": False, "seconds_to_target": spp_needed * per_spp,
            "spp_to_target_rel_mse": spp_rel, "extrapolated_rel_mse": False,
            "seconds_to_target_rel_mse": spp_rel * per_spp}
    def curve_row(points, rmse_key, rel_key, per_spp):
        # samplers whose error is not ~ 1/spp (Sobol, multijitter): read off their error curve, at
        # that curve's own speed
        spp_needed, extrapolated = spp_to_reach(points, rmse_key, target)
        spp_rel, extrapolated_rel = spp_to_reach(points, rel_key, target_rel, power=1.0)
        return {"spp_per_s": 1.0 / per_spp, "samples_per_s": pixels / per_spp, "timing": None,
                "rmse_at_target_spp": value_at(points, rmse_key, "spp", target_spp),
                "rel_mse_at_target_spp": value_at(points, rel_key, "spp", target_spp), "measured": "curve",
                "spp_to_target": spp_needed, "extrapolated": extrapolated, "seconds_to_target": spp_needed * per_spp,
                "spp_to_target_rel_mse": spp_rel, "extrapolated_rel_mse": extrapolated_rel,
                "seconds_to_target_rel_mse": spp_rel * per_spp}

    curves = {(c["integrator"], c["sampler"]): c for c in cornell["curves"]}
    for (integrator, sampler), c in curves.items():
        if combo(integrator, sampler) not in rows:
            rows[combo(integrator, sampler)] = curve_row(c["curve"], "rmse_mitsuba", "rel_mse_mitsuba",
                                                         c["seconds"] / c["spp"])
    last = ld_curve[-1]
    rows[f"mitsuba/{MITSUBA_LD_SAMPLER}"] = curve_row(ld_curve, "rmse", "rel_mse", last["seconds"] / last["spp"])

    # The best samplers again, over seeds: one curve is one image per spp (see step 4). Lantern's
    # renders return the image's read-back, which seeded_points calls after the clock stops.
    def lantern_sobol(integrator):
        def render(spp, seed):
            bench.renderer.reset()
            bench.renderer.render(bench.camera, spp, integrator, seed=seed, sampler="sobol")
            _sync()
            return bench.renderer.image, spp
        return render

    def mitsuba_ld(spp, seed):
        image = ms.render_scene(ld_scene, spp, seed=seed)
        return image, ms.samples_taken(ld_scene)

    renders = {name: (mitsuba_ld if name.startswith("mitsuba/") else lantern_sobol(name.split("/")[0]))
               for name in SEEDED_ROWS if name in rows}
    levels = seeded_levels([rows[name][key] for name in renders for key in ("spp_to_target", "spp_to_target_rel_mse")],
                           config.seeded_max_spp)
    seeds = range(config.seed + 15485863, config.seed + 15485863 + config.seeded_renders)
    seeded = seeded_points(renders, levels, seeds, ref) if levels else {}
    for name, points in seeded.items():
        row = rows[name]
        # time per spp: the top level's renders, taken in turn with the other rows' (as the
        # independent rows'), not the curve's, which ran at another moment than Mitsuba's
        top = points[-1]
        per_spp = top["seconds"] / top["spp"]
        row.update({"spp_per_s": 1.0 / per_spp, "samples_per_s": pixels / per_spp,
                    "timing": {"spp": top["spp"], "median_s": top["seconds"], "renders": top["renders"]}})
        spp_needed, extrapolated = spp_to_reach(points, "rmse", target)
        spp_rel, extrapolated_rel = spp_to_reach(points, "rel_mse", target_rel, power=1.0)
        row.update({"measured": "seeds", "seeded_points": points, "spp_to_target": spp_needed,
                    "extrapolated": extrapolated, "seconds_to_target": spp_needed * per_spp,
                    "spp_to_target_rel_mse": spp_rel, "extrapolated_rel_mse": extrapolated_rel,
                    "seconds_to_target_rel_mse": spp_rel * per_spp,
                    "rmse_at_target_spp": value_at(points, "rmse", "spp", target_spp),
                    "rel_mse_at_target_spp": value_at(points, "rel_mse", "spp", target_spp)})
    judged = rows.get(combo("mis", "independent"))
    passed = judged is not None and judged["seconds_to_target"] <= rows["mitsuba"]["seconds_to_target"]
    return {"available": True, "size": list(size), "max_depth": cornell["max_depth"], "threads": config.mitsuba_threads,
            "reference": {k: v for k, v in mitsuba_ref.items() if k not in ("scene", "image")},
            "target_spp": target_spp, "target_renders": config.mitsuba_target_renders, "target_rmse": target,
            "errors_per_seed": errors,
            "target_rel_mse": target_rel, "light_edge_pixels": int(edge.sum()), "light_edge_mse_share": edge_share,
            "curve": curve, "low_discrepancy_curve": {"sampler": MITSUBA_LD_SAMPLER, "points": ld_curve}, "rows": rows,
            "seeded": {"levels": levels, "renders": config.seeded_renders, "rows": list(seeded)},
            "lantern_curves": {combo(i, s): [{"spp": p["spp"], "seconds": p["seconds"], "rmse": p["rmse_mitsuba"]}
                                             for p in c["curve"]] for (i, s), c in curves.items()},
            "passed": passed}


def whole_process_comparison(config: IntegratorBenchConfig, max_depth: int) -> dict:
    """Lantern's `render` command against a Mitsuba process on the Cornell box, start to exit
    (renderer/bench/whole_process.py), both read against a Mitsuba reference of that size."""
    from renderer.bench import whole_process as wp

    size = config.whole_process_size
    log(f"[whole process] Mitsuba reference {size}x{size}, {config.whole_process_reference_spp} spp ...")
    reference = mitsuba_reference(replace(config, mitsuba_reference_spp=config.whole_process_reference_spp),
                                  (size, size), max_depth)
    whole = wp.WholeProcessConfig(size=size, spp=config.whole_process_spp, max_depth=max_depth,
                                  runs=config.whole_process_runs, threads=config.mitsuba_threads)
    log(f"[whole process] {whole.runs} runs of each command, alternating, after a warm-up run each ...")
    return wp.compare_or_note(whole, reference["image"].astype(np.float64), reference["spp"])


# --- report ------------------------------------------------------------------------------------

def print_report(results: list[dict], mitsuba: dict | None, config: IntegratorBenchConfig,
                 whole: dict | None = None, mesh: dict | None = None) -> None:
    print()
    compile_rows = []
    for res in results:
        for key, seconds in res.get("compile_s", {}).items():
            compile_rows.append([res["scene"], key, seconds])
        for key, error in res.get("errors", {}).items():
            compile_rows.append([res["scene"], key, f"FAILED: {error}"])
    if compile_rows:
        print_table(["scene", "integrator/sampler", "compile s"], compile_rows,
                    title="Compile time (first 1-spp launch: compilation or offline-cache load; not in any timing below)")
    for res in results:
        if "skipped" in res:
            print(f"{res['scene']}: skipped ({res['skipped']})\n")
            continue
        ref = res["reference"]
        floor = ref["noise_floor"]
        rows = []
        best = min(c["at_budget"]["rel_mse"] for c in res["curves"]) if res["curves"] else 1.0
        for c in res["curves"]:
            b = c["at_budget"]
            rows.append([combo(c["integrator"], c["sampler"]), round(b["spp"]), c["samples_per_s"] / 1e6, b["rmse"],
                         c["at_budget_floor_corrected"]["rmse"], b["rel_mse"], c["at_budget_floor_corrected"]["rel_mse"],
                         b["rel_mse_trimmed"], f"{b['rel_mse'] / best:.2f}x"])
        print_table(["integrator/sampler", "spp@T", "Msamples/s", "RMSE@T", "RMSE-floor", "relMSE@T", "relMSE-floor",
                     "relMSE*@T", "relMSE/best"], rows,
                    title=f"{res['scene']} ({res['size'][0]}x{res['size'][1]}, max depth {res['max_depth']}): equal time "
                          f"T = {config.budget_s:g} s. Reference: {ref['integrator']} {ref['spp']} spp in "
                          f"{ref['seconds']:.0f} s, its own noise: RMSE {floor['rmse']:.3g}, relMSE {floor['rel_mse']:.3g} "
                          f"(the floor; '-floor' columns subtract it). * = top {FIREFLY_TRIM:.1%} pixels left out")
        for key, error in res.get("errors", {}).items():
            print(f"   {key}: FAILED ({error})")
    if mitsuba is None:
        return
    if not mitsuba.get("available"):
        print(f"Mitsuba 3 comparison skipped: {mitsuba.get('note')}\n")
        return
    ref = mitsuba["reference"]
    rows = []
    m = mitsuba["rows"]["mitsuba"]
    for name, r in mitsuba["rows"].items():
        label = (f"Mitsuba {mitsuba['variant']}" if name == "mitsuba"
                 else f"Mitsuba {name.split('/')[1]}" if name.startswith("mitsuba/") else f"Lantern {name}")
        rows.append([label,
                     r["samples_per_s"] / 1e6, f"{r['samples_per_s'] / m['samples_per_s']:.2f}x",
                     r["rmse_at_target_spp"], r["rel_mse_at_target_spp"],
                     f"{r['spp_to_target']:.0f}" + ("(ext)" if r["extrapolated"] else ""),
                     r["seconds_to_target"], f"{m['seconds_to_target'] / r['seconds_to_target']:.2f}x",
                     f"{r['spp_to_target_rel_mse']:.0f}" + ("(ext)" if r["extrapolated_rel_mse"] else ""),
                     r["seconds_to_target_rel_mse"],
                     f"{m['seconds_to_target_rel_mse'] / r['seconds_to_target_rel_mse']:.2f}x"])
    n = mitsuba["target_spp"]
    print_table(["renderer", "Msamples/s", "vs Mitsuba", f"RMSE@{n}spp", f"relMSE@{n}spp", "spp to RMSE", "s to RMSE",
                 "speed (RMSE)", "spp to relMSE", "s to relMSE", "speed (relMSE)"], rows,
                title=f"Cornell box vs Mitsuba {mitsuba['version']} ({mitsuba['variant']}, {mitsuba['threads']} threads), "
                      f"{mitsuba['size'][0]}x{mitsuba['size'][1]}, max depth {mitsuba['max_depth']}, against a Mitsuba "
                      f"reference of {ref['spp']} spp (its own noise RMSE {ref['noise_floor']['rmse']:.3g}). Target: "
                      f"Mitsuba's RMSE {mitsuba['target_rmse']:.4g} (relMSE {mitsuba['target_rel_mse']:.4g}) at {n} spp. "
                      f"Independent-sampler rows: {mitsuba['target_renders']} renders of {n} spp each, round-robin "
                      f"(median time; mean squared error; spp to target from MSE ~ 1/spp). Sobol and Mitsuba "
                      f"{MITSUBA_LD_SAMPLER} rows: at their curves' speed, spp to target "
                      f"{_seeded_text(mitsuba.get('seeded'))}. "
                      f"speed = Mitsuba's seconds / the row's (>1: faster "
                      f"than Mitsuba); (ext) = extrapolated past the curve")
    print(f"   The RMSE is dominated by the {mitsuba['light_edge_pixels']} pixels on the light's edge "
          f"({mitsuba['light_edge_pixels'] / (mitsuba['size'][0] * mitsuba['size'][1]):.1%} of the image): they hold "
          f"{mitsuba['light_edge_mse_share']:.0%} of Mitsuba's squared error at the target, pixel-footprint noise "
          f"(an emitter ~20x brighter than the ceiling partly covering the pixel) that stratified pixel positions "
          f"(sobol) remove in a few spp. relMSE weighs those pixels down and measures the light transport.")
    r = mitsuba["rows"].get("mis/independent")
    if r is not None:
        print(f"Target (Lantern mis at least as fast as Mitsuba's LLVM CPU variant to the same RMSE): "
              f"{verdict(mitsuba['passed'])}  (Lantern mis {r['seconds_to_target']:.2f} s vs Mitsuba "
              f"{m['seconds_to_target']:.2f} s; samples/s {r['samples_per_s'] / 1e6:.2f} M vs "
              f"{m['samples_per_s'] / 1e6:.2f} M)")
    best, ld = mitsuba["rows"].get("mis/sobol"), mitsuba["rows"].get(f"mitsuba/{MITSUBA_LD_SAMPLER}")
    if best is not None and ld is not None:
        print(f"   Best sampler against best sampler: Lantern mis/sobol {best['seconds_to_target']:.2f} s vs Mitsuba "
              f"{MITSUBA_LD_SAMPLER} {ld['seconds_to_target']:.2f} s to the target RMSE "
              f"({ld['seconds_to_target'] / best['seconds_to_target']:.2f}x Mitsuba's speed)")
    if mitsuba.get("note"):
        print(f"   note: {mitsuba['note']}")
    print(flush=True)
    if whole is not None:
        from renderer.bench import whole_process as wp

        if whole.get("available"):
            print_table(wp.HEADERS, wp.summary_rows(whole), title=wp.caption(whole))
        else:
            print(f"Whole-process comparison not measured: {whole.get('note')}\n")
    if mesh is not None:
        from renderer.bench import mesh_heavy

        if mesh.get("available"):
            print_table(mesh_heavy.HEADERS, mesh_heavy.summary_rows(mesh), title=mesh_heavy.caption(mesh))
        else:
            print(f"Mesh-heavy comparison not measured: {mesh.get('note')}\n")


def _seeded_text(seeded: dict | None) -> str:
    """How the best samplers' spp to target were measured (step 4), for captions."""
    if not seeded or not seeded.get("rows"):
        return "read off their error curves"
    return (f"read off their error curves, or for {', '.join(seeded['rows'])} off the mean errors of "
            f"{seeded['renders']} seeds at {', '.join(map(str, seeded['levels']))} spp, rendered in turn "
            f"(speed: the median of the {seeded['levels'][-1]}-spp renders)")


_STYLE = {"path": "C0", "nee": "C1", "mis": "C2"}
_LINE = {"independent": "-", "sobol": "--"}


def write_plots(results: list[dict], mitsuba: dict | None, out_dir: Path, config: IntegratorBenchConfig,
                mesh: dict | None = None) -> list[Path]:
    plt = pyplot()
    written = []
    for res in results:
        if "skipped" in res or not res.get("curves"):
            continue
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
        floor = res["reference"]["noise_floor"]
        for ax, key, label, floor_value in ((axes[0], "rmse", "RMSE", floor["rmse"]),
                                             (axes[1], "rel_mse", "relMSE", floor["rel_mse"])):
            for c in res["curves"]:
                pts = [p for p in c["curve"] if p[key] > 0]
                ax.loglog([p["seconds"] for p in pts], [p[key] for p in pts], _LINE.get(c["sampler"], ":"),
                          color=_STYLE.get(c["integrator"]), marker=".", label=combo(c["integrator"], c["sampler"]))
            ax.axhline(floor_value, color="grey", ls=":", lw=1, label="reference's own noise")
            ax.axvline(config.budget_s, color="grey", ls="--", lw=1)
            ax.set_xlabel("render seconds (compile excluded)")
            ax.set_ylabel(f"{label} vs reference")
            ax.set_title(f"{res['scene']} {res['size'][0]}x{res['size'][1]}: {label} against time")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
        written.append(save_figure(fig, out_dir / f"bench_integrators_{res['scene']}.png"))
    if mitsuba and mitsuba.get("available"):
        fig, ax = plt.subplots(figsize=(6.5, 4.5))
        mc = mitsuba["curve"]
        ax.loglog([p["seconds"] for p in mc], [p["rmse"] for p in mc], "k-o", ms=3,
                  label=f"Mitsuba {mitsuba['variant']} ({mitsuba['threads']} threads)")
        for name, pts in mitsuba["lantern_curves"].items():
            integrator, sampler = name.split("/")
            ax.loglog([p["seconds"] for p in pts], [p["rmse"] for p in pts], _LINE.get(sampler, ":"),
                      color=_STYLE.get(integrator), marker=".", label=f"Lantern {name}")
        ax.axhline(mitsuba["target_rmse"], color="grey", ls=":", lw=1, label=f"target (Mitsuba {mitsuba['target_spp']} spp)")
        ax.set_xlabel("render seconds")
        ax.set_ylabel("RMSE vs Mitsuba reference")
        ax.set_title("Cornell box: Lantern vs Mitsuba 3")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        written.append(save_figure(fig, out_dir / "bench_integrators_mitsuba.png"))
    if mesh and mesh.get("available"):
        fig, ax = plt.subplots(figsize=(6.5, 4.5))
        for name, points in mesh["curves"].items():
            ax.loglog([p["seconds"] for p in points], [p["rel_mse_floor"] for p in points],
                      "-" if name.startswith("Lantern") else "--", marker=".", label=name)
        ax.axhline(mesh["target_rel_mse"], color="grey", ls=":", lw=1, label=f"target (Mitsuba {mesh['target_spp']} spp)")
        ax.set_xlabel("render seconds")
        ax.set_ylabel("relMSE vs own reference, its noise subtracted")
        ax.set_title(f"{mesh['scene']} {mesh['size'][0]}x{mesh['size'][1]}: Lantern vs Mitsuba 3")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        written.append(save_figure(fig, out_dir / "bench_integrators_mesh_heavy.png"))
    return written


# --- entry point ---------------------------------------------------------------------------------

def run(quick: bool = False, out_dir: Path = Path("reports"), scenes=None,
        config: IntegratorBenchConfig | None = None) -> int:
    """Benchmark the scenes (names or scene files; default config.scenes); print, write JSON and plots."""
    import warnings

    config = config or (QUICK if quick else FULL)
    if scenes is not None:
        config = replace(config, scenes=tuple(str(s) for s in scenes))
    out_dir = Path(out_dir)
    t_start = time.perf_counter()
    arch = speed_runtime()
    load_before = load_average()

    mitsuba_info = None
    mitsuba_ref = None
    if config.mitsuba and MITSUBA_SCENE in config.scenes:
        try:
            from renderer.bench import mitsuba_side

            mitsuba_info = mitsuba_side.availability()
        except Exception as error:  # noqa: BLE001 - the module itself may be missing or broken
            mitsuba_info = {"available": False, "note": f"renderer.bench.mitsuba_side unusable ({describe_error(error)})"}
        if mitsuba_info["available"] and not str(mitsuba_info["variant"]).startswith("llvm"):
            mitsuba_info = {**mitsuba_info, "note": (mitsuba_info.get("note") or "") + " (not the LLVM variant: "
                            "the comparison runs, but is not the one the target names)"}

    results = []
    for name in config.scenes:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # e.g. negative env-map pixels clamped: reported by `info`
                scene = load_named_scene(name)
        except Exception as error:  # noqa: BLE001 - e.g. a scene another change has not added yet
            results.append({"scene": Path(name).stem, "skipped": f"cannot load ({describe_error(error)})"})
            log(f"[{name}] skipped: {describe_error(error)}")
            continue
        extra = {}
        if scene.name == MITSUBA_SCENE and mitsuba_info and mitsuba_info["available"]:
            try:
                log(f"[{scene.name}] Mitsuba reference: {config.mitsuba_reference_spp} spp ...")
                mitsuba_ref = mitsuba_reference(config, scene_size(scene, config), scene.render.max_depth)
                extra["mitsuba"] = mitsuba_ref["image"]
                log(f"[{scene.name}]   {mitsuba_ref['spp']} spp in {mitsuba_ref['seconds']:.1f} s, noise RMSE "
                    f"{mitsuba_ref['noise_floor']['rmse']:.3g}")
            except Exception as error:  # noqa: BLE001
                mitsuba_info = {**mitsuba_info, "available": False,
                                "note": f"Mitsuba failed to render: {describe_error(error)}"}
                traceback.print_exc()
        try:
            results.append(bench_scene(scene, config, extra))
        except Exception as error:  # noqa: BLE001
            traceback.print_exc()
            results.append({"scene": scene.name, "skipped": f"failed ({describe_error(error)})"})

    mitsuba = None
    if mitsuba_info is not None:
        mitsuba = {"available": False, "note": mitsuba_info.get("note")}
        cornell = next((r for r in results if r["scene"] == MITSUBA_SCENE and "curves" in r), None)
        if mitsuba_info["available"] and mitsuba_ref is not None and cornell is not None:
            log("[mitsuba] error curve and samples/s ...")
            try:
                mitsuba = {**mitsuba_comparison(cornell, config, mitsuba_ref), "version": mitsuba_info["version"],
                           "variant": mitsuba_info["variant"], "note": mitsuba_info.get("note")}
            except Exception as error:  # noqa: BLE001
                traceback.print_exc()
                mitsuba = {"available": False, "note": f"comparison failed: {describe_error(error)}"}
        elif mitsuba_info["available"]:
            mitsuba["note"] = "the Cornell box did not render, nothing to compare"

    whole = None
    if config.whole_process and mitsuba is not None and mitsuba_info["available"] and mitsuba_ref is not None:
        cornell = next(r for r in results if r["scene"] == MITSUBA_SCENE)
        whole = whole_process_comparison(config, cornell["max_depth"])
    mesh = None
    if config.mesh_heavy != "off" and mitsuba_info is not None and mitsuba_info["available"]:
        from renderer.bench import mesh_heavy

        log("[mesh-heavy] Lantern and Mitsuba on the stress scene ...")
        mesh = mesh_heavy.compare_or_note(mesh_heavy.QUICK if config.mesh_heavy == "quick"
                                          else mesh_heavy.MeshHeavyConfig())
    for res in results:
        res.pop("renderer", None)
    print_report(results, mitsuba, config, whole, mesh)
    plots = write_plots(results, mitsuba, out_dir, config, mesh)
    total = time.perf_counter() - t_start
    report = {
        **report_header("integrators", quick, load_before, arch=arch, config=asdict(config)),
        "notes": ("Error vs reference: RMSE and relMSE = mean((x-ref)^2/(ref^2+1e-2)); rel_mse_trimmed leaves out the "
                  "0.1% pixels of largest error. Reference: mis, independent sampler, its own seed; its noise floor "
                  "is mean(film variance of the mean). Curves: one seed for every integrator and sampler, launches "
                  "of 1,1,2,4,... spp; seconds = wall-clock render time, compile excluded. at_budget: log-log "
                  "interpolation at the budget. Mitsuba: target RMSE = Mitsuba's at target_spp against a Mitsuba "
                  "reference; seconds_to_target = spp needed (from the curves) x measured seconds per spp."),
        "scenes": results,
        "mitsuba": {k: v for k, v in (mitsuba or {}).items()},
        "whole_process": whole,
        "mesh_heavy": mesh,
        "plots": [p.name for p in plots],
        "total_seconds": total,
    }
    path = write_json(out_dir / "bench_integrators.json", report)
    print(f"wrote {path} and {', '.join(p.name for p in plots)} in {out_dir}  (total {total:.0f} s)")
    return 0 if any("curves" in r for r in results) else 1

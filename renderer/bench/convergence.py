"""Error against time: the measurements every accuracy benchmark shares.

A progressive render from an empty film (launches of 1, 1, 2, 4, ... spp), curves read at a time or
an error (log-log interpolation), the noise floor a reference image adds to any comparison, the
same measurements over seeds, and one scene's Renderer with its compile times. `bench
integrators`, `denoise`, `photons` and the mesh-heavy comparison build on these.
"""
from __future__ import annotations

import math
import time

import numpy as np

from renderer.bench.common import REL_MSE_EPS, image_errors, rel_mse, rmse

REFERENCE_INTEGRATOR = "mis"
REFERENCE_SAMPLER = "independent"
FIREFLY_TRIM = 1e-3  # fraction of pixels with the largest error left out of relMSE*


def sync() -> None:
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
        sync()
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


def convergence(renderer, camera, integrator: str, sampler: str, references: dict, config,
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
            sync()
            self.compile_s[key] = time.perf_counter() - t0
        return self.compile_s[key]

    def reference(self, config) -> dict:
        """The long `mis` render: image, spp, seconds and its own noise floor."""
        run = progressive(self.renderer, self.camera, REFERENCE_INTEGRATOR, REFERENCE_SAMPLER, config.reference_seed,
                          config.reference_s, 1 << 24, max_launch_s=config.reference_launch_s)
        image = self.renderer.image()
        floor = noise_floor(image, self.renderer.film.variance_of_mean_image())
        return {"image": image, "integrator": REFERENCE_INTEGRATOR, "sampler": REFERENCE_SAMPLER,
                "seed": config.reference_seed, "spp": run["spp"], "seconds": run["seconds"], "noise_floor": floor,
                "rejected_samples": int(self.renderer.film.rejected_counts().sum())}

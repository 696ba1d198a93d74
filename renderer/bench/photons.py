"""`python app.py bench photons`: error against time of `mis` and `sppm` on the caustic scenes.

For `goblet` (light focused by a glass onto a table) and `pool` (sunlight focused by waves onto a
pool floor), in one process:

1. Compile both programs (1 spp / 1 iteration, reported separately).
2. Reference: a long `mis` render (unbiased) on its own seed. Caustics are exactly what `mis`
   converges slowly on, so the reference is itself noisy there: every error is also given
   floor-corrected, MSE - mean(reference variance of the mean), an unbiased estimate of the error
   against the true image since the reference and the test image are independent. (SPPM is biased
   but consistent: its error against the truth includes its remaining blur, which the correction
   does not remove.)
3. Error against time: `mis` in launches of 1, 1, 2, 4, ... spp and `sppm` in as many iterations,
   each from an empty film until the time budget; RMSE and relMSE over the whole image and over
   the scene's caustic region (a rectangle in image fractions, picked by eye from the reference
   renders: under the goblet's glass on the table; the pool floor seen through the water).
   The equal-time table reads the curves at the budget (log-log interpolation).

Target (the issue's): where the caustics are, `sppm` reaches a lower error than `mis` at equal time
(floor-corrected relMSE over the caustic region at the budget; PASS/FAIL per scene).

Writes <out_dir>/bench_photons.json and one log-log plot per scene.
"""
from __future__ import annotations

import math
import time
import warnings
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from renderer.bench.common import (REL_MSE_EPS, describe_error, load_average, load_named_scene, log, print_table, pyplot,
                                   rel_mse, report_header, rmse, save_figure, speed_runtime, verdict, write_json)
from renderer.bench.convergence import noise_floor, progressive, value_at

INTEGRATORS = ("mis", "sppm")
SAMPLER = "independent"
# (x0, y0, x1, y1) as fractions of the image, y from the top.
CAUSTIC_REGIONS = {"goblet": (0.30, 0.62, 0.72, 0.98), "pool": (0.08, 0.45, 0.70, 0.95)}


@dataclass(frozen=True)
class PhotonBenchConfig:
    size: tuple[int, int] = (160, 90)
    budget_s: float = 20.0
    reference_s: float = 180.0
    reference_launch_s: float = 3.0
    max_spp: int = 1 << 16
    seed: int = 1
    reference_seed: int = 7919
    scenes: tuple[str, ...] = ("goblet", "pool")


FULL = PhotonBenchConfig()
QUICK = PhotonBenchConfig(size=(96, 54), budget_s=4.0, reference_s=20.0, reference_launch_s=2.0)


def region_mask(shape: tuple[int, int], region: tuple[float, float, float, float]) -> np.ndarray:
    """(H, W) bool mask of a rectangle given in image fractions (y from the top)."""
    h, w = shape
    x0, y0, x1, y1 = region
    mask = np.zeros((h, w), bool)
    mask[int(y0 * h):max(int(y1 * h), int(y0 * h) + 1), int(x0 * w):max(int(x1 * w), int(x0 * w) + 1)] = True
    return mask


def errors(image: np.ndarray, reference: np.ndarray, mask: np.ndarray) -> dict:
    return {"rmse": rmse(image, reference), "rel_mse": rel_mse(image, reference),
            "rmse_caustic": rmse(image[mask], reference[mask]), "rel_mse_caustic": rel_mse(image[mask], reference[mask])}


def floor_of(reference: np.ndarray, variance: np.ndarray, mask: np.ndarray) -> dict:
    whole = noise_floor(reference, variance)
    region = noise_floor(reference[mask], variance[mask])
    return {"mse": whole["mse"], "rel_mse": whole["rel_mse"], "mse_caustic": region["mse"],
            "rel_mse_caustic": region["rel_mse"]}


def corrected(at: dict, floor: dict) -> dict:
    """Floor-corrected errors (clipped at 0: the floor is an estimate too)."""
    return {"rmse": math.sqrt(max(at["rmse"] ** 2 - floor["mse"], 0.0)),
            "rel_mse": max(at["rel_mse"] - floor["rel_mse"], 0.0),
            "rmse_caustic": math.sqrt(max(at["rmse_caustic"] ** 2 - floor["mse_caustic"], 0.0)),
            "rel_mse_caustic": max(at["rel_mse_caustic"] - floor["rel_mse_caustic"], 0.0)}


def bench_scene(scene, config: PhotonBenchConfig) -> dict:
    import taichi as ti

    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    renderer = Renderer(scene, config.size)
    camera = CameraFrame.from_spec(scene.camera)
    region = CAUSTIC_REGIONS.get(scene.name)
    mask = region_mask((config.size[1], config.size[0]), region or (0.0, 0.0, 1.0, 1.0))
    result = {"scene": scene.name, "size": list(config.size), "caustic_region": region,
              "caustic_pixels": int(mask.sum()), "compile_s": {}}
    for integrator in INTEGRATORS:
        renderer.reset()
        t0 = time.perf_counter()
        renderer.render(camera, 1, integrator, sampler=SAMPLER, seed=0)
        ti.sync()
        result["compile_s"][integrator] = time.perf_counter() - t0
        log(f"[{scene.name}] {integrator}: first launch {result['compile_s'][integrator]:.1f} s")

    log(f"[{scene.name}] reference: mis for {config.reference_s:g} s ...")
    run = progressive(renderer, camera, "mis", SAMPLER, config.reference_seed, config.reference_s, 1 << 24,
                      max_launch_s=config.reference_launch_s)
    reference = renderer.image()
    floor = floor_of(reference, renderer.film.variance_of_mean_image(), mask)
    result["reference"] = {"spp": run["spp"], "seconds": run["seconds"], "noise_floor": floor}

    curves = {}
    for integrator in INTEGRATORS:
        log(f"[{scene.name}] {integrator}: {config.budget_s:g} s ...")
        curve = progressive(renderer, camera, integrator, SAMPLER, config.seed, config.budget_s, config.max_spp,
                            observe=lambda image: errors(image, reference, mask))
        points = curve["points"]
        at = {key: value_at(points, key, "seconds", config.budget_s) for key in
              ("rmse", "rel_mse", "rmse_caustic", "rel_mse_caustic")}
        curves[integrator] = {"curve": points, "spp": curve["spp"], "seconds": curve["seconds"],
                              "at_budget": at, "at_budget_floor_corrected": corrected(at, floor)}
    result["curves"] = curves
    mis = curves["mis"]["at_budget_floor_corrected"]["rel_mse_caustic"]
    sppm = curves["sppm"]["at_budget_floor_corrected"]["rel_mse_caustic"]
    result["target"] = {"mis": mis, "sppm": sppm, "passed": sppm < mis}
    return result


def print_report(results: list[dict], config: PhotonBenchConfig) -> None:
    for res in results:
        if "skipped" in res:
            print(f"{res['scene']}: skipped ({res['skipped']})\n")
            continue
        ref = res["reference"]
        rows = []
        for integrator, c in res["curves"].items():
            raw, cor = c["at_budget"], c["at_budget_floor_corrected"]
            rows.append([integrator, res["compile_s"][integrator], c["spp"], raw["rmse"], cor["rmse"], raw["rel_mse"],
                         cor["rel_mse"], raw["rmse_caustic"], cor["rmse_caustic"], raw["rel_mse_caustic"],
                         cor["rel_mse_caustic"]])
        w, h = res["size"]
        print_table(["integrator", "first launch s", "spp/iter", "RMSE", "-floor", "relMSE", "-floor",
                     "caustic RMSE", "-floor", "caustic relMSE", "-floor"], rows,
                    title=f"{res['scene']} {w}x{h}, at {config.budget_s:g} s (reference: mis, {ref['spp']} spp in "
                          f"{ref['seconds']:.0f} s; caustic region {res['caustic_pixels']} pixels)")
        t = res["target"]
        print(f"Target ({res['scene']}): sppm's caustic relMSE (floor-corrected) below mis's at equal time: "
              f"{t['sppm']:.4g} vs {t['mis']:.4g}  {verdict(t['passed'])}\n")


def write_plots(results: list[dict], out_dir: Path) -> list[Path]:
    plt = pyplot()
    paths = []
    for res in results:
        if "curves" not in res:
            continue
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
        for ax, key, label in ((axes[0], "rel_mse", "whole image"), (axes[1], "rel_mse_caustic", "caustic region")):
            for integrator, c in res["curves"].items():
                pts = c["curve"]
                ax.loglog([p["seconds"] for p in pts], [max(p[key], 1e-12) for p in pts], marker="o", label=integrator)
            floor = res["reference"]["noise_floor"][key]
            ax.axhline(floor, color="grey", linestyle=":", label="reference noise floor")
            ax.set_xlabel("seconds")
            ax.set_ylabel("relMSE")
            ax.set_title(f"{res['scene']}: {label}")
            ax.legend()
        paths.append(save_figure(fig, Path(out_dir) / f"bench_photons_{res['scene']}.png"))
    return paths


def run(quick: bool = False, out_dir: Path = Path("reports"), scenes=None, config: PhotonBenchConfig | None = None) -> int:
    config = config or (QUICK if quick else FULL)
    if scenes is not None:
        config = replace(config, scenes=tuple(str(s) for s in scenes))
    t_start = time.perf_counter()
    arch = speed_runtime()
    load_before = load_average()
    results = []
    for name in config.scenes:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                scene = load_named_scene(name)
            results.append(bench_scene(scene, config))
        except Exception as error:  # noqa: BLE001 - one scene must not end the benchmark
            results.append({"scene": Path(name).stem, "skipped": describe_error(error)})
    print_report(results, config)
    plots = write_plots(results, out_dir)
    report = {**report_header("photons", quick, load_before, arch=arch, config=asdict(config)),
              "rel_mse_eps": REL_MSE_EPS, "scenes": results, "plots": [p.name for p in plots],
              "total_seconds": time.perf_counter() - t_start}
    path = write_json(Path(out_dir) / "bench_photons.json", report)
    print(f"wrote {path}  (total {report['total_seconds']:.0f} s)")
    return 0 if any("curves" in r for r in results) else 1

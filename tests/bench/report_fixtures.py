"""Small benchmark reports shaped exactly like the benchmarks' own (the keys renderer/bench/*.py
write), for the benchmark page's tests. Where a benchmark's code computes a part of its report
from plain numbers (headers, timings, paired differences, ratios, summaries, targets) that code
computes it here too, and every plot is drawn by the benchmark's own plotting code, so the
PNG names are the ones a real run lists. The figures are made up, small and fixed."""
from __future__ import annotations

import math
import random
from dataclasses import asdict
from pathlib import Path

import numpy as np

from renderer.bench.common import ErrorDifference, Timing, report_header, write_json
from renderer.scene.description import MarchSettings

LOAD = [0.5, 0.25, 0.125]  # load averages before each fake run


def _header(name: str, quick: bool = False, **fields) -> dict:
    return report_header(name, quick, LOAD, **fields)


def _write(out_dir: Path, name: str, report: dict) -> dict:
    write_json(Path(out_dir) / f"bench_{name}.json", report)
    return report


# --- sdf -----------------------------------------------------------------------------------------

def _sdf_curve(final_error: float, rate: float, spp: int) -> list[dict]:
    points, done = [], 0
    while done < spp:
        done = min(spp, max(1, 2 * done))
        error = final_error * spp / done
        points.append({"spp": done, "render_s": done / rate, "rmse": math.sqrt(error), "rel_mse": 1.1 * error,
                       "rel_mse_trimmed": error, "seconds": done / rate})
    return points


def _sdf_scene(name: str, config, scene_omega: float, reductions: dict, sweep_errors: dict) -> dict:
    """reductions: omega -> fraction of march steps saved; sweep_errors: sweep key -> path relMSE*
    at equal time per swept value."""
    march = MarchSettings(hit_threshold=1.0, max_steps=64, over_relaxation=scene_omega)
    base_steps, base_seconds = 40.0, 0.2
    rows = []
    for omega in config.omegas:
        saved = reductions[omega]
        seconds = base_seconds * (1.0 - 0.5 * saved)
        path = ErrorDifference("rel_mse", 0.010 + 0.002 * saved, 0.010, 0.002 * saved, 0.001, 1e-3)
        geometry = ErrorDifference("mse", 1e-4, 1e-4, 0.0, 1e-5)
        rows.append({
            "omega": omega, "path_seconds": seconds, "path_timing": Timing([seconds] * 3, [1.0]).as_dict(),
            "samples_per_s": config.compare_spp * 32 * 18 / seconds, "speedup": base_seconds / seconds,
            "speedup_min": base_seconds / seconds, "steps_per_ray": base_steps * (1.0 - saved), "step_reduction": saved,
            "primary_steps_per_ray": 30.0 * (1.0 - saved), "primary_step_reduction": saved,
            "rmse": 0.1, "rel_mse": 0.012, "rel_mse_trimmed": path.a, "path_vs_plain": path.as_dict(),
            "geometry_rmse": 0.01, "geometry_vs_plain": geometry.as_dict(), "geometry_seconds": 0.05,
            "equal_error": saved < 0.5})
    judged = min(rows, key=lambda r: abs(r["omega"] - scene_omega))
    target = {"omega": judged["omega"], "step_reduction": judged["step_reduction"],
              "equal_error": judged["equal_error"], "path_z": judged["path_vs_plain"]["z"],
              "geometry_z": judged["geometry_vs_plain"]["z"],
              "passed": judged["step_reduction"] >= 0.25 and judged["equal_error"],
              "omegas_meeting_target": [r["omega"] for r in rows if r["step_reduction"] >= 0.25 and r["equal_error"]]}
    sweeps = {}
    for key, values in (("hit_threshold", config.thresholds), ("max_steps", config.step_limits)):
        sweep_rows = []
        for value, error in zip(values, sweep_errors[key]):
            rate = 40.0
            curve = _sdf_curve(error, rate, 8)
            sweep_rows.append({"value": value, "geometry_seconds": 0.05, "geometry_rmse": 0.01,
                               "geometry_rel_mse": 0.002, "primary_steps_per_ray": 20.0, "path_spp_per_s": rate,
                               "samples_per_s": rate * 32 * 18,
                               "path": {"curve": curve, "steps_per_ray": 25.0,
                                        **{k: v for k, v in curve[-1].items() if k != "seconds"}}})
        sweeps[key] = {"default": getattr(march, key), "equal_time_s": config.sweep_seconds, "rows": sweep_rows}
    plain = MarchSettings(hit_threshold=0.25, max_steps=1024, over_relaxation=1.0)
    return {"scene": name, "march_default": asdict(march), "march_reference": asdict(plain), "build_s": 0.5,
            "compile_s": {"path": 2.0, "normals": 1.0},
            "reference": {"integrator": "path", "spp": 16, "seed": 104729, "seconds": 3.0, "steps_per_ray": 45.0,
                          "noise_floor": {"mse": 1e-5, "rel_mse": 1e-4}, "geometry_integrator": "normals",
                          "geometry_spp": 2, "geometry_seed": 1, "geometry_steps_per_ray": 44.0},
            "over_relaxation": rows, "target": target, "sweeps": sweeps, "seconds": 20.0}


def sdf_report(out_dir: Path) -> dict:
    from renderer.bench import sdf

    config = sdf.SdfBenchConfig(size=(32, 18), compare_spp=2, omegas=(1.0, 1.6), thresholds=(0.5, 2.0),
                                step_limits=(8, 64), sweep_seconds=0.25)
    scenes = [_sdf_scene("alpha", config, 1.6, {1.0: 0.0, 1.6: 0.3}, {"hit_threshold": [3e-3, 2e-3],
                                                                      "max_steps": [5e-3, 1e-3]}),
              _sdf_scene("beta", config, 1.6, {1.0: 0.0, 1.6: 0.2}, {"hit_threshold": [1e-3, 4e-3],
                                                                     "max_steps": [6e-3, 2e-3]})]
    plots = sdf.write_plots(scenes, out_dir)
    return _write(out_dir, "sdf", {
        **_header("sdf", arch="cpu", config=asdict(config)),
        "targets": {"step_reduction": sdf.STEP_REDUCTION_TARGET, "worse_if_z_above": sdf.EQUAL_ERROR_Z,
                    "and_relative_difference_above": sdf.EQUAL_ERROR_MARGIN, "firefly_trim": sdf.FIREFLY_TRIM},
        "notes": "made up", "scenes": scenes, "plots": [p.name for p in plots], "total_seconds": 40.0})


# --- startup -------------------------------------------------------------------------------------

def _child(mode: str, start: float, kernels: float, frame: float) -> dict:
    """One child process's result, parsed by the benchmark's own parser from its printed line."""
    import json

    from renderer.bench import startup

    names = ["launch", "main", "imported", "initialised"]
    names += ["app_built", "first_window_frame"] if mode == "viewer" else ["scene_loaded", "built"]
    marks, t = {}, 1000.0
    for name in names:
        marks[name] = t
        t += start / len(names)
    marks["first_frame"] = t + kernels + frame
    marks["second_frame"] = marks["first_frame"] + frame
    child = {"mode": mode, "marks": marks, "size": [960, 540]}
    if mode == "viewer":
        child["moving"] = {"frames": 60, "median_ms": 48.0, "p90_ms": 55.0, "sizes": [[480, 270]]}
    stdout = startup.MARKER + json.dumps(child) + "\n"
    return startup.parse_child_output(stdout, "", 0, marks["second_frame"] - marks["launch"] + 0.2, mode)


def _cold_warm(mode: str, optimize: str, cold_kernels: float, warm_kernels: float, frame: float) -> dict:
    from renderer.bench import startup

    warm = [_child(mode, 1.0, warm_kernels, frame) for _ in range(2)]
    return {"mode": mode, "optimize": optimize, "cold": _child(mode, 1.2, cold_kernels, frame), "warm_runs": warm,
            "warm": startup.summarise(warm), "cache_bytes": 12_500_000}


def startup_report(out_dir: Path) -> dict:
    from renderer.bench import startup

    measurements = [_cold_warm("renderer", "compile", 30.0, 0.8, 1.3), _cold_warm("viewer", "compile", 31.0, 0.9, 0.1)]
    full = _cold_warm("renderer", "run", 120.0, 1.5, 1.0)
    levels = [startup.optimization_level(measurements[0]), startup.optimization_level(full)]
    targets = startup.start_up_targets(measurements)
    measurements.append(full)
    return _write(out_dir, "startup", {
        **_header("startup", scene="showcase", size=[960, 540]), "target_seconds": startup.TARGET_SECONDS,
        "notes": "made up", "measurements": measurements, "targets": targets, "optimization_levels": levels,
        "viewer_note": None, "total_seconds": 300.0})


# --- bvh -----------------------------------------------------------------------------------------

def _rates(rays: int, seconds: float) -> dict:
    from renderer.bench.rays import ray_rates

    return ray_rates(rays, Timing([seconds, seconds * 1.1, seconds * 0.9]))


def _bvh_mesh(name: str, triangles: int, speed: dict) -> dict:
    from renderer.bench import bvh_measure, embree_side

    t = np.array([1.0, 2.0, -1.0, 4.0], np.float32)
    agreement = embree_side.agreement(t, t, t >= 0)
    builds, configs = [], []
    for strategy, build_s, cost in (("sah", 0.5, 40.0), ("midpoint", 0.1, 55.0), ("equal_count", 0.2, 50.0)):
        per = 60.0 if strategy == "sah" else 62.0
        builds.append({"strategy": strategy, "max_leaf_size": 4, "seconds": build_s,
                       "timing": Timing([build_s] * 3).as_dict(), "triangles_per_s": triangles / build_s,
                       "builder_threads": 2, "sah_cost": cost, "nodes": triangles // 2, "leaves": triangles // 4,
                       "mean_leaf_size": 3.5, "largest_leaf": 4, "depth": 20,
                       "device_bytes": {"bvh": int(24 * triangles), "triangles": int(36 * triangles),
                                        "total": int(per * triangles), "per_triangle": per, "bvh_per_triangle": 24.0,
                                        "target_passed": per <= bvh_measure.BYTES_PER_TRIANGLE_TARGET}})
        for traversal in bvh_measure.TRAVERSALS:
            for test in bvh_measure.TRIANGLE_TESTS:
                base, leaves = bvh_measure.traversal_and_leaves(traversal)
                rate = (speed[strategy] * {"stack": 1.0, "stackless": 0.8}.get(base, 1.25)
                        * (1.0 if test == "watertight" else 1.1) * (1.2 if leaves == "packets" else 1.0))
                entry = {"strategy": strategy, "traversal": traversal, "triangle_test": test, "compile_s": 1.5}
                for kind, scale in (("coherent", 3.0), ("incoherent", 1.0)):
                    entry[kind] = {**_rates(1 << 16, (1 << 16) / (rate * scale * 1e6)), "nodes_per_ray": 30.0,
                                   "tests_per_ray": 8.0, "hit_fraction": 0.6, "agreement": agreement}
                configs.append(entry)
    embree = {"available": True, "build_s": 0.05, "upload_s": 0.01, "robust": True, "trace_threads": 2,
              "coherent": {**_rates(1 << 16, 0.005), "hit_fraction": 0.6},
              "incoherent": {**_rates(1 << 16, 0.02), "hit_fraction": 0.6}}
    mesh = {"name": name, "triangles": triangles, "bounds": [[0, 0, 0], [1, 1, 1]], "bounds_s": 0.01, "build_runs": 3,
            "configs": configs, "builds": builds, "rays": {"coherent": {"count": 1 << 16, "camera": [256, 256]},
                                                          "incoherent": {"count": 1 << 16}},
            "embree": embree}
    default = next(c for c in configs if (c["strategy"], c["traversal"], c["triangle_test"]) == bvh_measure.DEFAULT)
    best = max(configs, key=lambda c: c["incoherent"]["mrays_per_s"])
    mesh["default_config"] = bvh_measure.config_name(*bvh_measure.DEFAULT)
    mesh["best_incoherent_config"] = bvh_measure.config_name(best["strategy"], best["traversal"], best["triangle_test"])
    mesh["ratio_to_embree"] = bvh_measure._embree_ratios(mesh, default, ("coherent", "incoherent"))
    mesh["embree_target_passed"] = mesh["ratio_to_embree"]["incoherent"]["default"] >= bvh_measure.EMBREE_RATIO_TARGET
    mesh["agreement_all_configs"] = {"coherent": 1.0, "incoherent": 0.9995}
    mesh["wide_vs_binary"] = bvh_measure.wide_vs_binary(configs)
    mesh["packets_vs_scalar"] = bvh_measure.packets_vs_scalar(configs)
    mesh["shadow"] = {"config": mesh["default_config"], "rays": 1 << 16, "occluded_mrays_per_s": 5.0,
                      "closest_mrays_per_s": 3.0, "occluded_fraction": 0.4, "closest_hit_fraction": 0.4,
                      "closest_nodes_per_ray": 25.0, "timing": {}, "consistent_with_closest": 1.0,
                      "embree_occluded_mrays_per_s": 12.0, "embree_occluded_fraction": 0.4,
                      "agreement_with_embree": 1.0}
    return mesh


def bvh_report(out_dir: Path) -> dict:
    from renderer.bench import bvh, bvh_measure, bvh_report as plots

    config = bvh_measure.BvhBenchConfig(meshes=(), camera=(256, 256), incoherent_rays=1 << 16, leaf_sizes=(2, 4))
    meshes = [_bvh_mesh("small", 5_000, {"sah": 4.0, "midpoint": 2.0, "equal_count": 3.0}),
              _bvh_mesh("large", 1_000_000, {"sah": 2.0, "midpoint": 0.5, "equal_count": 1.0})]
    leaf_rows = [{"max_leaf_size": leaf, "build_s": 0.4, "timing": Timing([0.4]).as_dict(), "compile_s": 1.0,
                  "device_bytes": {"per_triangle": bytes_, "bvh_per_triangle": bytes_ - 36.0},
                  "sah_cost": 40.0, "nodes": 1000, "leaves": 500, "mean_leaf_size": 2.0, "largest_leaf": leaf,
                  "depth": 18, "incoherent": {**_rates(1 << 16, 0.02), "nodes_per_ray": 30.0, "tests_per_ray": 8.0,
                                              "hit_fraction": 0.6}}
                 for leaf, bytes_ in ((2, 70.0), (4, 60.0))]
    leaf_rows[0]["incoherent"] = {**_rates(1 << 16, 0.03), "nodes_per_ray": 35.0, "tests_per_ray": 6.0,
                                  "hit_fraction": 0.6}
    leaf = {"mesh": "large", "triangles": 1_000_000, "config": "sah/stack/watertight", "rays": 1 << 16,
            "rows": leaf_rows, "best_max_leaf_size": 4, "within_tie_of_best": [4],
            "tie_fraction": bvh_measure.LEAF_TIE, "renderer_default": bvh_measure.DEFAULT_LEAF}
    embree_info = {"available": True, "version": "Embree version:  4.4.0 (embreex 4.4.0.post1)"}
    report = {**_header("bvh", arch="cpu", threads={"taichi": 2, "bvh_builder": [2], "embree_trace": 2,
                                                    "embree_build": 2}, embree=embree_info,
                        config={**asdict(config), "meshes": []}),
              "targets": bvh._targets(meshes, True), "notes": bvh.NOTES, "meshes": meshes, "leaf_size": leaf}
    report["plots"] = [p.name for p in plots.write_plots(report, out_dir)]
    report["total_seconds"] = 200.0
    return _write(out_dir, "bvh", report)


# --- integrators ---------------------------------------------------------------------------------

def _integrator_curve(integrator: str, sampler: str, error_at_1s: float, budget: float) -> dict:
    from renderer.bench.convergence import value_at

    points, spp, seconds = [], 1, 0.0
    while seconds < budget:
        seconds = spp * 0.05
        error = error_at_1s / seconds
        points.append({"spp": spp, "seconds": seconds, "rmse": math.sqrt(error), "rel_mse": error,
                       "rel_mse_trimmed": 0.9 * error})
        spp *= 2
    at = {key: value_at(points, key, "seconds", budget) for key in ("rmse", "rel_mse", "rel_mse_trimmed")}
    at["spp"] = value_at(points, "spp", "seconds", budget)
    return {"integrator": integrator, "sampler": sampler, "curve": points, "spp": points[-1]["spp"],
            "seconds": points[-1]["seconds"], "samples_per_s": points[-1]["spp"] * 64 * 64 / points[-1]["seconds"],
            "at_budget": at, "rejected_samples": 0,
            "at_budget_floor_corrected": {"rmse": math.sqrt(max(at["rmse"] ** 2 - 1e-6, 0.0)),
                                          "rel_mse": max(at["rel_mse"] - 1e-5, 0.0)}}


def integrators_report(out_dir: Path, errors: dict | None = None) -> dict:
    """errors: scene -> {integrator/sampler: relMSE after one second} (the default: mis/sobol best)."""
    from renderer.bench import integrators
    from renderer.bench.integrator_config import IntegratorBenchConfig

    config = IntegratorBenchConfig(square_size=(64, 64), wide_size=(96, 54), budget_s=2.0,
                                   scenes=("box", "room"), mitsuba=False)
    errors = errors or {scene: {"path/independent": 0.4, "path/sobol": 0.3, "nee/independent": 0.1,
                                "nee/sobol": 0.08, "mis/independent": 0.05, "mis/sobol": 0.02}
                        for scene in config.scenes}
    results = []
    for scene, per_combo in errors.items():
        curves = [_integrator_curve(*name.split("/"), error, config.budget_s) for name, error in per_combo.items()]
        results.append({"scene": scene, "size": [64, 64], "max_depth": 8, "build_s": 0.2, "errors": {},
                        "compile_s": {name: 1.0 for name in per_combo},
                        "reference": {"integrator": "mis", "sampler": "independent", "seed": 104729, "spp": 512,
                                      "seconds": 8.0, "noise_floor": {"mse": 1e-6, "rmse": 1e-3, "rel_mse": 1e-5},
                                      "rejected_samples": 0},
                        "curves": curves})
    results.append({"scene": "missing_scene", "skipped": "cannot load (SceneError: no such scene)"})
    mitsuba = {"available": False, "note": "Mitsuba 3 is not installed"}
    plots = integrators.write_plots(results, mitsuba, out_dir, config)
    return _write(out_dir, "integrators", {
        **_header("integrators", arch="cpu", config=asdict(config)), "notes": "made up", "scenes": results,
        "mitsuba": mitsuba, "whole_process": _whole_process(), "mesh_heavy": _mesh_heavy(),
        "plots": [p.name for p in plots],
        "total_seconds": 120.0})


def _mesh_heavy() -> dict:
    def row(samples_per_s, spp, seconds, speed):
        return {"samples_per_s": samples_per_s, "spp_to_target": spp, "extrapolated": False,
                "seconds_to_target": seconds, "speed": speed}

    rows = {"Mitsuba path/independent": row(1.5e6, 64.0, 2.5, 1.0), "Mitsuba path/multijitter": row(1.4e6, 40.0, 1.6, 1.56),
            "Lantern mis/independent": row(0.5e6, 60.0, 7.0, 0.36), "Lantern mis/sobol": row(0.45e6, 30.0, 3.8, 0.66)}
    return {"available": True, "scene": "stress", "size": [320, 180], "max_depth": 8, "target_spp": 64,
            "target_rel_mse": 0.0123, "threads": 2,
            "references": {"mitsuba": {"spp": 1024, "seconds": 60.0, "noise_floor": {"rel_mse": 1e-4}},
                           "lantern": {"spp": 900, "seconds": 60.0, "noise_floor": {"rel_mse": 2e-4}}},
            "references_rel_mse": 0.004, "compile_s": {"mis/independent": 30.0}, "curves": {}, "rows": rows,
            "best_lantern": "Lantern mis/sobol", "best_mitsuba": "Mitsuba path/multijitter", "best_ratio": 1.6 / 3.8,
            "passed": False}


def _whole_process() -> dict:
    lantern = {"command": "python app.py render cornell_box ...", "warmup_s": 30.0, "seconds": [21.0, 20.0, 22.5],
               "median_s": 21.0, "rmse": 0.0123, "render_median_s": 18.5, "outside_render_median_s": 2.5}
    mitsuba = {"command": "python -m renderer.bench.mitsuba_process ...", "warmup_s": 12.0,
               "seconds": [9.5, 9.0, 9.25], "median_s": 9.25, "rmse": 0.0131, "render_median_s": 8.75,
               "outside_render_median_s": 0.5}
    return {"available": True, "size": 256, "spp": 256, "max_depth": 8, "integrator": "mis", "runs": 3, "threads": 2,
            "reference_spp": 1024, "lantern": lantern, "mitsuba": mitsuba, "ratio": 21.0 / 9.25,
            "render_ratio": 18.5 / 8.75, "target_ratio": 1.5, "passed": False}


# --- features ------------------------------------------------------------------------------------

def _build(role: str, times: list[float], own: list[float], effect: str | None = None, **extra) -> dict:
    from renderer.bench.features import paired_ratio

    return {"role": role, "effect": effect, "variant": "own", "pinhole": False, "compile_s": 2.0, "times_s": times,
            "samples_per_s": 4 * 64 * 36 / float(np.median(times)), "vs_own": paired_ratio(times, own, seed=1),
            "rejected": 0, "finite": True, **extra}


def features_report(out_dir: Path) -> dict:
    from renderer.bench import features

    config = features.QUICK
    own = [0.10, 0.11, 0.10, 0.12, 0.10]
    scenes = []
    for name, slower in (("alpha", 1.05), ("beta", 1.30)):
        builds = {"own": _build("own", own, own),
                  "everything": _build("everything", [t * slower for t in own], own),
                  "+dielectric": _build("unused", [t * 1.01 for t in own], own, "dielectric", image_vs_own=0.0,
                                        identical_to_own=True),
                  "+media": _build("unused", [t * 0.9 for t in own], own, "has_media", image_vs_own=0.0,
                                   identical_to_own=True)}
        cases = []
        if name == "beta":
            builds["no glass"] = _build("case", [t * 0.8 for t in own], own)
            cases.append({"effect": "glass", "scene": "beta", "with_build": "own", "without": "no glass",
                          "ratio": features.paired_ratio(own, builds["no glass"]["times_s"], seed=1),
                          "seconds_with": 0.1, "seconds_without": 0.08, "image_difference": 0.3, "noise_floor": 0.05,
                          "mean_change": -0.1, "mean_change_floor": 0.01, "image_spp": 16})
        scenes.append({"scene": name, "geometry": "sdf", "renderers_s": 0.3, "own_features": "made up",
                       "own_effects": [], "cases": cases, "builds": builds, "pass_spp": 4, "seconds": 30.0})
    scenes.append({"scene": "gamma", "error": "timed out after 1800 s"})
    summary = features.summarise(scenes, config)
    plot = features.write_plot(scenes, out_dir)
    return _write(out_dir, "features", {
        **_header("features", quick=True, integrator=features.INTEGRATOR, config=asdict(config)),
        "skipped_scenes": ["stress"], "rule": "made up", "notes": "made up", "missing": [], "summary": summary,
        "scenes": scenes, "plot": plot.name, "total_seconds": 90.0})


# --- photons -------------------------------------------------------------------------------------

def photons_report(out_dir: Path) -> dict:
    from renderer.bench import photons

    config = photons.PhotonBenchConfig(size=(32, 18), budget_s=2.0, scenes=("goblet",))
    floor = {"mse": 1e-5, "rel_mse": 1e-4, "mse_caustic": 4e-5, "rel_mse_caustic": 4e-4}
    curves = {}
    for integrator, caustic in (("mis", 0.05), ("sppm", 0.01)):
        points = [{"spp": n, "seconds": 0.25 * n, "rmse": 0.1 / n, "rel_mse": 0.02 / n, "rmse_caustic": 0.2 / n,
                   "rel_mse_caustic": caustic * 8 / n} for n in (1, 2, 4, 8)]
        at = {key: photons.value_at(points, key, "seconds", config.budget_s)
              for key in ("rmse", "rel_mse", "rmse_caustic", "rel_mse_caustic")}
        curves[integrator] = {"curve": points, "spp": 8, "seconds": 2.0, "at_budget": at,
                              "at_budget_floor_corrected": photons.corrected(at, floor)}
    mis = curves["mis"]["at_budget_floor_corrected"]["rel_mse_caustic"]
    sppm = curves["sppm"]["at_budget_floor_corrected"]["rel_mse_caustic"]
    scene = {"scene": "goblet", "size": [32, 18], "caustic_region": photons.CAUSTIC_REGIONS["goblet"],
             "caustic_pixels": 120, "compile_s": {"mis": 3.0, "sppm": 4.0},
             "reference": {"spp": 256, "seconds": 20.0, "noise_floor": floor}, "curves": curves,
             "target": {"mis": mis, "sppm": sppm, "passed": sppm < mis}}
    plots = photons.write_plots([scene], out_dir)
    return _write(out_dir, "photons", {
        **_header("photons", arch="cpu", config=asdict(config)), "rel_mse_eps": 1e-2, "scenes": [scene],
        "plots": [p.name for p in plots], "total_seconds": 60.0})


# --- interactive ---------------------------------------------------------------------------------

def _frames(ms: float, n: int = 12) -> list[float]:
    return [ms / 1000 * (1 + 0.05 * (i % 3)) for i in range(n)]


def interactive_report(out_dir: Path) -> dict:
    from renderer.bench import interactive

    rng = random.Random(1)
    results = []
    for scene, integrator, still_ms, moving_ms in (("box", "path", 40.0, 45.0), ("box", "mis", 60.0, 50.0)):
        still = {"frames": 12, "frame_ms_median": still_ms, "frame_ms_max": 1.1 * still_ms,
                 "latency_ms": [1000 * v for v in interactive.event_latencies(_frames(still_ms), rng)],
                 "samples_per_s": 2e6, "input_seen_in_frame": True}
        whole = {**still, "samples_per_s": 2.05e6, "frame_ms_median": 3 * still_ms,
                 "latency_ms": [1000 * v for v in interactive.event_latencies(_frames(3 * still_ms), rng)]}
        still["rate_ratio"] = still["samples_per_s"] / whole["samples_per_s"]
        if integrator == "mis":  # a report from before the first round was measured has none (path)
            still["first_round"] = {"seconds": 0.5, "pixel_samples": 9e5, "samples_per_s": 1.8e6,
                                    "rate_ratio": 1.8e6 / whole["samples_per_s"]}
        moving = {"frames": 12, "frame_ms_median": moving_ms, "frame_ms_max": 1.1 * moving_ms,
                  "latency_ms": [1000 * v for v in interactive.event_latencies(_frames(moving_ms), rng)],
                  "input_seen_in_frame": True}
        latencies = still["latency_ms"] + moving["latency_ms"]
        results.append({"scene": scene, "integrator": integrator,
                        "switch": {"first_image_s": 1.5, "frames": 3, "notice_frames": 1, "longest_frame_s": 1.2},
                        "still": still, "still_whole_samples": whole, "moving": moving,
                        "latency_p50_ms": interactive.percentile(latencies, 0.5),
                        "latency_p95_ms": interactive.percentile(latencies, 0.95),
                        "whole_samples_p95_ms": interactive.percentile(whole["latency_ms"] + moving["latency_ms"],
                                                                       0.95),
                        "still_p95_ms": interactive.percentile(still["latency_ms"], 0.95),
                        "moving_p95_ms": interactive.percentile(moving["latency_ms"], 0.95)})
    results.append({"scene": "room", "integrator": "sppm", "skipped": "RuntimeError: made up"})
    measured = [r for r in results if "skipped" not in r]
    latency_ok = all(r["latency_p95_ms"] <= interactive.TARGET_LATENCY_MS for r in measured)
    rate_ok = all(r["still"]["rate_ratio"] >= interactive.TARGET_STILL_RATE for r in measured)
    plot = interactive.write_plot(results, out_dir)
    config = {**interactive.QUICK, "scenes": ("box", "room")}
    return _write(out_dir, "interactive", {
        **_header("interactive", quick=True, arch="cpu", config=config),
        "latency_target_ms": interactive.TARGET_LATENCY_MS, "still_rate_target": interactive.TARGET_STILL_RATE,
        "latency_ok": latency_ok, "rate_ok": rate_ok, "results": results, "plots": [plot.name], "total_seconds": 30.0})


# --- denoise -------------------------------------------------------------------------------------

def _denoise_scene(name: str, gain: float, adaptive_gain: float, config) -> dict:
    """gain: denoised relMSE / raw relMSE; adaptive_gain: adaptive relMSE / uniform relMSE at equal time."""
    from renderer.bench.denoise import DEFAULT_THRESHOLD, paired_verdict
    from renderer.bench.convergence import spp_to_reach

    floor = 1e-4
    points, spp = [], 1
    while spp <= config.max_spp:
        raw = 0.08 / spp
        points.append({"spp": spp, "seconds": 0.1 * spp, "denoise_s": 0.01, "raw": raw, "denoised": gain * raw,
                       "raw_corrected": max(raw - floor, 0.0), "denoised_corrected": max(gain * raw - floor, 0.0),
                       "denoised_quick_corrected": max(1.2 * gain * raw - floor, 0.0)})
        spp *= 2
    by_spp = {p["spp"]: p for p in points}
    at8 = by_spp[8]
    reach, extrapolated = spp_to_reach(points, "raw_corrected", max(at8["denoised_corrected"], 1e-12), power=1.0)
    raw128 = by_spp.get(128) or points[-1]
    uniform = by_spp[config.equal_time_spp]
    error = adaptive_gain * uniform["raw"]
    difference = error - uniform["raw"]
    paired = {"metric": "rel_mse", "trim": 0.0, "a": error, "b": uniform["raw"], "difference": difference,
              "relative_difference": difference / uniform["raw"], "standard_error": 0.2 * abs(difference) + 1e-9,
              "z": difference / (0.2 * abs(difference) + 1e-9)}
    adaptive = [{"threshold": threshold, "seconds": uniform["seconds"], "max_spp": 32, "mean_spp": 6.5,
                 "stopped_fraction": 0.4, "rel_mse": error, "rel_mse_corrected": max(error - floor, 0.0),
                 "paired": paired, "paired_trimmed": {**paired, "trim": 1e-3}}
                for threshold in config.thresholds]
    default = next(a for a in adaptive if a["threshold"] == DEFAULT_THRESHOLD)
    return {"scene": name, "size": list(config.size), "compile_s": 2.0,
            "reference": {"spp": 1024, "seconds": 8.0, "rel_mse_floor": floor}, "curve": points,
            "raw_spp_matching_denoised_8": {"spp": reach, "extrapolated": extrapolated},
            "target_denoise": {"denoised_8": at8["denoised_corrected"], "raw_128": raw128["raw_corrected"],
                               "raw_spp": raw128["spp"], "passed": at8["denoised_corrected"] < raw128["raw_corrected"]},
            "uniform": {"spp": uniform["spp"], "seconds": uniform["seconds"], "rel_mse": uniform["raw"],
                        "rel_mse_corrected": uniform["raw_corrected"]},
            "adaptive": adaptive,
            "target_adaptive": {"threshold": default["threshold"], "adaptive": default["rel_mse_corrected"],
                                "uniform": uniform["raw_corrected"],
                                "passed": default["rel_mse_corrected"] < uniform["raw_corrected"],
                                "paired": paired_verdict(paired), "paired_trimmed": paired_verdict(paired)},
            "viewer_size": {"size": [960, 540], "reference": {"spp": 512, "seconds": 120.0, "rel_mse_floor": floor},
                            "feature_boost": 4 if name == "room" else 0, "with_features_boost": 4,
                            "raw_8": 0.01, "denoised_8": (0.5 if name == "room" else 1.0) * gain * 0.01,
                            "denoised_8_with_features": 0.5 * gain * 0.01, "denoised_8_without_features": gain * 0.01,
                            "raw_128": 0.01 / 16, "seconds_8": 2.5 if name == "room" else 1.5,
                            "seconds_8_with_features": 2.5, "seconds_8_without_features": 1.5, "seconds_128": 25.0,
                            "passed": (0.5 if name == "room" else 1.0) * gain * 0.01 < 0.01 / 16}}


def denoise_report(out_dir: Path) -> dict:
    from renderer.bench import denoise

    config = denoise.DenoiseBenchConfig(size=(32, 18), max_spp=16, equal_time_spp=8,
                                        thresholds=(0.02, denoise.DEFAULT_THRESHOLD), scenes=("box", "room", "hall"))
    scenes = [_denoise_scene("box", 0.05, 0.8, config), _denoise_scene("room", 0.2, 1.1, config),
              {"scene": "hall", "skipped": "SceneError: made up"}]
    plots = denoise.write_plots(scenes, out_dir)
    return _write(out_dir, "denoise", {
        **_header("denoise", arch="cpu", config=asdict(config)), "denoiser_frame_s": 0.125, "denoiser_frame_quick_s": 0.03,
        "frame_size": [960, 540], "scenes": scenes, "plots": [p.name for p in plots], "total_seconds": 80.0})


# --- texture-filter ------------------------------------------------------------------------------

def texture_filter_report(out_dir: Path) -> dict:
    from renderer.bench import texture_filter

    config = texture_filter.QUICK
    curves = {f: [{"spp": n, "seconds": 0.01 * n * cost, "rmse": error / n ** 0.5} for n in config.horizon_spp]
              for f, cost, error in (("trilinear", 1.1, 0.14), ("anisotropic", 1.25, 0.1), ("none", 1.0, 0.2))}
    report = {"horizon": {"reference_spp": config.reference_spp, "curves": curves},
              "speeds": [{"scene": scene, "first_frame_s": {"trilinear": 9.8, "anisotropic": 10.1, "none": 9.5},
                          "msamples_per_s": {}, "median": {"trilinear": 2.4, "anisotropic": 2.2, "none": 2.7},
                          "relative": {"trilinear": 2.4 / 2.7, "anisotropic": 2.2 / 2.7, "none": 1.0}}
                         for scene in ("textured", "cornell_box")],
              "denoise_target": {"size": list(config.size), "reference": {"spp": 900, "seconds": 8.0,
                                                                         "rel_mse_floor": 1e-4},
                                 "filters": {f: {"seconds_8": 0.2, "raw_8": 0.05, "denoised_8": d, "denoised_quick_8": 1.1 * d,
                                                 "seconds_32": 0.8,
                                                 "raw_32": 0.012, "passed": d < 0.012}
                                             for f, d in (("trilinear", 0.01), ("anisotropic", 0.009),
                                                          ("none", 0.015))}}}
    plot = texture_filter.write_plot(report, out_dir)
    return _write(out_dir, "texture-filter", {
        **_header("texture-filter", quick=True, arch="cpu", config=asdict(config)), **report, "plots": [plot.name],
        "total_seconds": 50.0})


WRITERS = {"sdf": sdf_report, "startup": startup_report, "bvh": bvh_report, "integrators": integrators_report,
           "features": features_report, "photons": photons_report, "interactive": interactive_report,
           "denoise": denoise_report, "texture-filter": texture_filter_report}

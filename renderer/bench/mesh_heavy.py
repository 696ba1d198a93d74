"""Lantern against Mitsuba 3 on a mesh-heavy scene, at equal error: `bench integrators`' second
comparison (the first is the Cornell box's, renderer/bench/integrators.py).

The scene is assets/scenes/stress.toml: a million-triangle terrain, a glass and a gold sphere
under sunset.exr. Mitsuba renders the same geometry, camera and environment with its nearest
materials (renderer.bench.mitsuba_side.stress_scene_dict), so the two images differ a little, and
each renderer's error is read against its own reference: Lantern's `mis` (independent sampler,
its own seed) for `reference_s` seconds, Mitsuba's `path` in independent passes. Each reference's
own noise (the film's variance of the mean; the spread of Mitsuba's passes) is subtracted from
the errors against it (relMSE - floor), and the two references' relMSE against each other says
how alike the renderers draw the scene.

Curves: Lantern's `mis` with the independent and the Sobol sampler, progressive (launches of 1,
1, 2, 4, ... spp up to `budget_s`); Mitsuba's `path` with its independent and its multijitter
sampler, separate renders at 1, 2, 4, ... spp (JIT warmed up first). The target is Mitsuba's
independent relMSE at `target_spp`; each row's spp and seconds to reach it come from its curve
(log-log interpolation; past its end extrapolated as relMSE ~ 1/spp, and flagged). Target (issue:
closer to the hardware): Lantern's best row at most as slow as Mitsuba's best to that error.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from renderer.bench.common import describe_error, load_named_scene, log, rel_mse
from renderer.bench.convergence import SceneBench, noise_floor, progressive, spp_to_reach

SCENE = "stress"
LANTERN_ROWS = (("mis", "independent"), ("mis", "sobol"))
MITSUBA_SAMPLERS = ("independent", "multijitter")
MIN_ERROR = 1e-12  # floor-corrected errors are clipped here (a curve may dip below its reference's noise)


@dataclass(frozen=True)
class MeshHeavyConfig:
    size: tuple[int, int] = (320, 180)
    max_depth: int = 8
    budget_s: float = 10.0  # each Lantern curve
    reference_s: float = 60.0  # Lantern's reference
    reference_launch_s: float = 3.0
    mitsuba_reference_spp: int = 1024
    mitsuba_pass_spp: int = 128
    mitsuba_curve_max_spp: int = 256
    target_spp: int = 64
    threads: int = 2
    seed: int = 1
    reference_seed: int = 104729


QUICK = MeshHeavyConfig(size=(96, 54), budget_s=2.0, reference_s=8.0, reference_launch_s=1.0,
                        mitsuba_reference_spp=256, mitsuba_pass_spp=64, mitsuba_curve_max_spp=64, target_spp=16)


def _corrected(value: float, floor: float) -> float:
    return max(value - floor, MIN_ERROR)


def mitsuba_side_of(config: MeshHeavyConfig) -> dict:
    """Mitsuba's reference (mean of independent passes, its floor) and its curves."""
    from renderer.bench import mitsuba_side as ms

    mi, _, _ = ms._import_mitsuba()
    ms.set_threads(config.threads)
    width, height = config.size
    scene_dict = ms.stress_scene_dict(width, height, config.max_depth)
    scenes = {}
    for sampler in MITSUBA_SAMPLERS:
        spec = dict(scene_dict)
        spec["sensor"] = {**scene_dict["sensor"], "sampler": {"type": sampler, "sample_count": 16}}
        scenes[sampler] = mi.load_dict(spec)
        ms.render_scene(scenes[sampler], 1, seed=0)  # JIT warm-up
    passes = max(2, config.mitsuba_reference_spp // config.mitsuba_pass_spp)
    t0 = time.perf_counter()
    images = np.stack([ms.render_scene(scenes["independent"], config.mitsuba_pass_spp,
                                       seed=config.reference_seed + k).astype(np.float64) for k in range(passes)])
    reference = images.mean(axis=0)
    floor = noise_floor(reference, images.var(axis=0, ddof=1) / passes)
    out = {"reference": {"spp": passes * config.mitsuba_pass_spp, "seconds": time.perf_counter() - t0,
                         "noise_floor": floor}, "image": reference, "curves": {}}
    for sampler, scene in scenes.items():
        points, spp = [], 1
        while spp <= config.mitsuba_curve_max_spp:
            t0 = time.perf_counter()
            image = ms.render_scene(scene, spp, seed=config.seed + spp)
            seconds = time.perf_counter() - t0
            error = rel_mse(image, reference)
            points.append({"spp": ms.samples_taken(scene), "seconds": seconds, "rel_mse": error,
                           "rel_mse_floor": _corrected(error, floor["rel_mse"])})
            spp *= 2
        out["curves"][sampler] = points
    return out


def lantern_side_of(config: MeshHeavyConfig) -> dict:
    """Lantern's reference (its floor) and its curves, in this process."""
    scene = load_named_scene(SCENE)
    bench = SceneBench(scene, config.size)
    for integrator, sampler in LANTERN_ROWS:
        bench.compile(integrator, sampler)
    run = progressive(bench.renderer, bench.camera, "mis", "independent", config.reference_seed, config.reference_s,
                      1 << 24, max_launch_s=config.reference_launch_s)
    reference = bench.renderer.image().astype(np.float64)
    floor = noise_floor(reference, bench.renderer.film.variance_of_mean_image())
    out = {"reference": {"spp": run["spp"], "seconds": run["seconds"], "noise_floor": floor}, "image": reference,
           "curves": {}, "compile_s": dict(bench.compile_s)}
    for integrator, sampler in LANTERN_ROWS:
        def observe(image):
            error = rel_mse(image, reference)
            return {"rel_mse": error, "rel_mse_floor": _corrected(error, floor["rel_mse"])}

        points = progressive(bench.renderer, bench.camera, integrator, sampler, config.seed, config.budget_s,
                             1 << 16, observe)["points"]
        out["curves"][f"{integrator}/{sampler}"] = points
    return out


def row_to_target(points: list[dict], pixels: int, target: float) -> dict:
    """Samples/s over the curve, and the spp and seconds at which it reaches `target`."""
    spp, extrapolated = spp_to_reach(points, "rel_mse_floor", target, power=1.0)
    # Mitsuba's points are separate renders, Lantern's cumulative (one progressive film): either
    # way the last (largest) point's seconds / spp is the curve's time per spp
    per_spp = points[-1]["seconds"] / points[-1]["spp"]
    return {"samples_per_s": pixels / per_spp, "spp_to_target": spp, "extrapolated": extrapolated,
            "seconds_to_target": spp * per_spp}


def compare(config: MeshHeavyConfig) -> dict:
    mitsuba = mitsuba_side_of(config)
    log(f"[mesh-heavy] Mitsuba: reference {mitsuba['reference']['spp']} spp in {mitsuba['reference']['seconds']:.1f} s")
    lantern = lantern_side_of(config)
    log(f"[mesh-heavy] Lantern: reference {lantern['reference']['spp']} spp in {lantern['reference']['seconds']:.1f} s")
    pixels = config.size[0] * config.size[1]
    target_point = next(p for p in mitsuba["curves"]["independent"] if p["spp"] == config.target_spp)
    target = target_point["rel_mse_floor"]
    rows = {}
    for sampler, points in mitsuba["curves"].items():
        rows[f"Mitsuba path/{sampler}"] = row_to_target(points, pixels, target)
    for name, points in lantern["curves"].items():
        rows[f"Lantern {name}"] = row_to_target(points, pixels, target)
    base = rows["Mitsuba path/independent"]["seconds_to_target"]
    for row in rows.values():
        row["speed"] = base / row["seconds_to_target"]
    best_lantern = min((r["seconds_to_target"], n) for n, r in rows.items() if n.startswith("Lantern"))
    best_mitsuba = min((r["seconds_to_target"], n) for n, r in rows.items() if n.startswith("Mitsuba"))
    return {
        "scene": SCENE, "size": list(config.size), "max_depth": config.max_depth, "target_spp": config.target_spp,
        "target_rel_mse": target, "threads": config.threads,
        "references": {"mitsuba": mitsuba["reference"], "lantern": lantern["reference"]},
        "references_rel_mse": rel_mse(lantern["image"], mitsuba["image"]),
        "compile_s": lantern["compile_s"],
        "curves": {**{f"Mitsuba path/{s}": p for s, p in mitsuba["curves"].items()},
                   **{f"Lantern {n}": p for n, p in lantern["curves"].items()}},
        "rows": rows, "best_lantern": best_lantern[1], "best_mitsuba": best_mitsuba[1],
        "best_ratio": best_mitsuba[0] / best_lantern[0], "passed": best_lantern[0] <= best_mitsuba[0],
    }


def compare_or_note(config: MeshHeavyConfig) -> dict:
    try:
        return {"available": True, **compare(config)}
    except Exception as error:  # noqa: BLE001 - one failed comparison must not end the benchmark
        return {"available": False, "note": describe_error(error)}


HEADERS = ["renderer", "Msamples/s", "spp to target", "seconds to target", "speed"]


def summary_rows(result: dict) -> list[list]:
    return [[name, r["samples_per_s"] / 1e6, f"{r['spp_to_target']:.0f}" + (" (ext)" if r["extrapolated"] else ""),
             r["seconds_to_target"], f"{r['speed']:.2f}x"] for name, r in result["rows"].items()]


def caption(result: dict) -> str:
    refs = result["references"]
    return (f"Mesh-heavy scene ({result['scene']}: a million-triangle terrain, glass and gold spheres, an HDR sunset) "
            f"at {result['size'][0]}x{result['size'][1]}, max depth {result['max_depth']}: each renderer against its "
            f"own reference (Lantern mis {refs['lantern']['spp']:,} spp, Mitsuba path {refs['mitsuba']['spp']:,} spp; "
            f"their own noise subtracted; the two references differ by relMSE {result['references_rel_mse']:.3g}, "
            f"Mitsuba's materials being its nearest). Target: Mitsuba's independent relMSE at {result['target_spp']} "
            f"spp ({result['target_rel_mse']:.3g}); speed = Mitsuba independent's seconds to it / the row's. Best "
            f"against best ({result['best_lantern']} vs {result['best_mitsuba']}): {result['best_ratio']:.2f}x "
            f"Mitsuba's speed, {'PASS' if result['passed'] else 'FAIL'}.")

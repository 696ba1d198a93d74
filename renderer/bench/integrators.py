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
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np

from renderer.bench.convergence import (FIREFLY_TRIM, REFERENCE_INTEGRATOR, REFERENCE_SAMPLER, SceneBench, combo,
                                        convergence, seeded_levels, seeded_points, spp_to_reach,
                                        sync, value_at)
from renderer.bench.integrator_config import (FULL, MITSUBA_LD_SAMPLER, MITSUBA_SCENE, QUICK, SEEDED_ROWS,
                                              IntegratorBenchConfig)
from renderer.bench.mitsuba_side import mitsuba_reference
from renderer.bench.whole_process import whole_process_comparison
from renderer.bench.common import (
    describe_error,
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
            sync()
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
            sync()
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

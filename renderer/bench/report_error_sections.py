"""The benchmark page's sections of the error-against-time benchmarks (sdf, integrators, photons,
denoise): their main tables rendered from the JSON reports, and what each knob costs, in words
computed from the same figures. The key names are those renderer/bench/sdf.py, integrators.py,
photons.py and denoise.py write."""
from __future__ import annotations

from collections import Counter

from renderer.bench import mesh_heavy, whole_process
from renderer.bench.common import Z_SIGNIFICANT, paired_text
from renderer.bench.report_markdown import (
    MISSING,
    Section,
    details,
    listing,
    num,
    pct,
    spread,
    table,
    times,
    verdict,
)


def most_common(values: list) -> tuple[object, int]:
    """(the most frequent value, its count); ties go to the value seen first."""
    counts = Counter(values)
    best = max(counts.values())
    return next(v for v in values if counts[v] == best), best


def _skipped(entries: list[dict]) -> list[str]:
    return [f"{e.get('scene', '?')}: {e.get('skipped') or e.get('error')}" for e in entries
            if "skipped" in e or "error" in e]


def _skipped_block(entries: list[dict]) -> list[str]:
    lines = _skipped(entries)
    return ["Not measured: " + "; ".join(lines) + "."] if lines else []


# --- sdf -----------------------------------------------------------------------------------------

def _lowest_error_value(sweep: dict):
    """The swept value with the lowest path-traced relMSE* at the sweep's equal time."""
    return min(sweep["rows"], key=lambda r: r["path"]["rel_mse_trimmed"])["value"]


def _judged_row(scene: dict) -> dict:
    return next(r for r in scene["over_relaxation"] if r["omega"] == scene["target"]["omega"])


def _sdf_scene_details(scene: dict) -> str:
    rows = []
    for r in scene["over_relaxation"]:
        pd, gd = r["path_vs_plain"], r["geometry_vs_plain"]
        rows.append([r["omega"], r["steps_per_ray"], pct(-r["step_reduction"], signed=True), r["primary_steps_per_ray"],
                     r["samples_per_s"] / 1e6, times(r["speedup"]), r["rel_mse_trimmed"],
                     f"{pct(pd['relative_difference'], 2, True)} (z {num(pd['z'])})", r["geometry_rmse"],
                     f"{pct(gd['relative_difference'], 2, True)} (z {num(gd['z'])})",
                     "yes" if r["equal_error"] else "no"])
    parts = ["Over-relaxation at equal spp (path-traced relMSE* against the reference; geometry = RMSE of the "
             "normals view against plain sphere tracing; Δ = paired difference against ω = 1):",
             table(["ω", "steps/ray", "vs ω 1", "camera-ray steps", "Msamples/s", "speed", "relMSE*", "Δ relMSE*",
                    "geometry RMSE", "Δ geometry MSE", "equal error"], rows)]
    for key, sweep in scene["sweeps"].items():
        rows = [[("*" if r["value"] == sweep["default"] else "") + num(r["value"]), r["geometry_seconds"],
                 r["geometry_rmse"], r["primary_steps_per_ray"], r["samples_per_s"] / 1e6, r["path"]["spp"],
                 r["path"]["rel_mse_trimmed"]] for r in sweep["rows"]]
        parts += [f"Sweep of `{key}` (* = the scene's value; path at equal time T = {num(sweep['equal_time_s'])} s):",
                  table([key, "geometry s", "geometry RMSE", "camera-ray steps", "path Msamples/s", "spp at T",
                         "relMSE* at T"], rows)]
    return details(f"{scene['scene']}: every ω and every sweep setting", "\n\n".join(parts))


def sdf_section(report: dict) -> Section:
    entries = report.get("scenes", [])
    scenes = [s for s in entries if "over_relaxation" in s]
    target = report.get("targets", {}).get("step_reduction")
    rows = []
    for s in scenes:
        m, t = s["march_default"], s["target"]
        rows.append([s["scene"], f"{num(m['hit_threshold'])} / {num(m['max_steps'])} / {num(m['over_relaxation'])}",
                     t["omega"], pct(t["step_reduction"]), times(_judged_row(s)["speedup"]),
                     "yes" if t["equal_error"] else "no", verdict(t["passed"]),
                     num(_lowest_error_value(s["sweeps"]["hit_threshold"])),
                     num(_lowest_error_value(s["sweeps"]["max_steps"]))])
    section = Section()
    if not scenes:
        section.blocks += _skipped_block(entries)
        return section
    config = report.get("config", {})
    w, h = config.get("size", ("?", "?"))
    section.blocks.append(
        f"Per scene at {w}x{h}: the scene's march settings (hit threshold in pixel footprints / step limit / ω); "
        f"over-relaxation at the scene's ω against plain sphere tracing at equal spp (fewer march steps, path "
        f"samples/s, error no worse in both paired tests); target: at least {pct(target, 0)} fewer steps at equal "
        f"error; and the hit threshold and step limit with the lowest path-traced relMSE* (top 0.1 % pixels left "
        f"out) at equal time.")
    section.blocks.append(table(["scene", "threshold / steps / ω", "ω", "fewer steps", "speed", "equal error",
                                 "target", "best threshold at T", "best step limit at T"], rows))
    section.blocks += [_sdf_scene_details(s) for s in scenes]
    section.blocks += _skipped_block(entries)

    met = sum(1 for s in scenes if s["target"]["passed"])
    section.findings.append(
        f"At each scene's own over-relaxation, sphere tracing takes "
        f"{spread([s['target']['step_reduction'] for s in scenes], pct)} fewer march steps than plain sphere tracing "
        f"(ω = 1) and path-traces at {spread([_judged_row(s)['speedup'] for s in scenes], times)} its speed; "
        f"{met} of {len(scenes)} scenes meet the target of {pct(target, 0)} fewer steps at equal error.")
    equal_time = scenes[0]["sweeps"]["hit_threshold"]["equal_time_s"]
    parts = []
    for key, label in (("hit_threshold", "hit threshold"), ("max_steps", "step limit")):
        value, count = most_common([_lowest_error_value(s["sweeps"][key]) for s in scenes])
        worst = [max(r["path"]["rel_mse_trimmed"] for r in s["sweeps"][key]["rows"])
                 / min(r["path"]["rel_mse_trimmed"] for r in s["sweeps"][key]["rows"]) for s in scenes]
        parts.append(f"{label} {num(value)} gives the lowest error on {count} of {len(scenes)} scenes, the worst "
                     f"{label} ending at {spread(worst, times)} the lowest")
    section.findings.append(f"Given the same {num(equal_time)} s of path tracing, " + "; ".join(parts) + ".")
    return section


# --- integrators ---------------------------------------------------------------------------------

def _combo(curve: dict) -> str:
    return f"{curve['integrator']}/{curve['sampler']}"


def _best_at_budget(scene: dict) -> dict:
    return min(scene["curves"], key=lambda c: c["at_budget"]["rel_mse"])


def _mitsuba_block(mitsuba: dict) -> list[str]:
    if not mitsuba:
        return []
    if not mitsuba.get("available"):
        return [f"Lantern against Mitsuba 3: not measured ({mitsuba.get('note') or 'Mitsuba unavailable'})."]
    base = mitsuba["rows"]["mitsuba"]
    rows = []
    for name, r in mitsuba["rows"].items():
        label = (f"Mitsuba {mitsuba.get('variant', '')}".strip() if name == "mitsuba"
                 else f"Mitsuba {name.split('/', 1)[1]}" if name.startswith("mitsuba/") else f"Lantern {name}")
        rows.append([label, r["samples_per_s"] / 1e6, r["rmse_at_target_spp"],
                     num(r["spp_to_target"]) + (" (extrapolated)" if r["extrapolated"] else ""),
                     r["seconds_to_target"], times(base["seconds_to_target"] / r["seconds_to_target"])])
    ref = mitsuba["reference"]
    n = mitsuba["target_spp"]
    seeded = mitsuba.get("seeded") or {}
    how = (f" The independent rows: {mitsuba.get('target_renders')} renders of {n} spp each, in turn; "
           f"the other rows' spp to target read off their error curves")
    if seeded.get("rows"):
        how += (f", except {listing(seeded['rows'])}: mean errors of {seeded['renders']} seeds at "
                f"{listing([str(v) for v in seeded['levels']])} spp, rendered in turn, and timed by the "
                f"{seeded['levels'][-1]}-spp renders")
    caption = (f"Lantern against Mitsuba {mitsuba.get('version', '')} ({mitsuba.get('variant', '')}, "
               f"{mitsuba['threads']} threads) on the Cornell box at {mitsuba['size'][0]}x{mitsuba['size'][1]}, max "
               f"depth {mitsuba['max_depth']}, against a Mitsuba reference of {num(ref['spp'])} spp. Target: "
               f"Mitsuba's RMSE at {n} spp ({num(mitsuba['target_rmse'])}); speed = Mitsuba's seconds to it / the "
               f"row's. Lantern mis at least as fast as Mitsuba: {verdict(mitsuba.get('passed'))}.{how}.")
    return [caption, table(["renderer", "Msamples/s", f"RMSE at {n} spp", "spp to target", "seconds to target",
                            "speed"], rows)]


def _comparison_block(result: dict | None, what: str, module) -> list[str]:
    """A Mitsuba comparison's caption and table (module: whole_process or mesh_heavy, each with
    caption, HEADERS and summary_rows), or why it was not measured."""
    if not result:
        return []
    if not result.get("available"):
        return [f"{what}: not measured ({result.get('note')})."]
    return [module.caption(result), table(module.HEADERS, module.summary_rows(result))]


def integrators_section(report: dict) -> Section:
    entries = report.get("scenes", [])
    scenes = [s for s in entries if s.get("curves")]
    budget = report.get("config", {}).get("budget_s")
    section = Section()
    for s in scenes:
        ref, floor = s["reference"], s["reference"]["noise_floor"]
        best = _best_at_budget(s)["at_budget"]["rel_mse"]
        rows = [[_combo(c), round(c["at_budget"]["spp"]), c["samples_per_s"] / 1e6, c["at_budget"]["rmse"],
                 c["at_budget"]["rel_mse"], c["at_budget_floor_corrected"]["rel_mse"],
                 c["at_budget"]["rel_mse_trimmed"], times(c["at_budget"]["rel_mse"] / best)] for c in s["curves"]]
        section.blocks += [
            f"**{s['scene']}** ({s['size'][0]}x{s['size'][1]}, max depth {s['max_depth']}) at equal time T = "
            f"{num(budget)} s; reference: {ref['integrator']}, {num(ref['spp'])} spp in {num(ref['seconds'])} s, "
            f"its own noise relMSE {num(floor['rel_mse'])} (the floor; '−floor' subtracts it).",
            table(["integrator/sampler", "spp at T", "Msamples/s", "RMSE", "relMSE", "relMSE −floor", "relMSE*",
                   "relMSE / best"], rows)]
    section.blocks += _mitsuba_block(report.get("mitsuba") or {})
    section.blocks += _comparison_block(report.get("whole_process"), "Whole-process time against Mitsuba 3",
                                        whole_process)
    section.blocks += _comparison_block(report.get("mesh_heavy"), "Lantern against Mitsuba 3 on a mesh-heavy scene",
                                        mesh_heavy)
    compile_rows = [[s["scene"], name, seconds] for s in scenes for name, seconds in s.get("compile_s", {}).items()]
    if compile_rows:
        section.blocks.append(details("Compile times (first 1 spp launch: compilation or offline-cache load)",
                                      table(["scene", "integrator/sampler", "seconds"], compile_rows)))
    section.blocks += _skipped_block(entries)
    if not scenes:
        return section

    winners: dict[str, list[str]] = {}
    for s in scenes:
        winners.setdefault(_combo(_best_at_budget(s)), []).append(s["scene"])
    said = "; ".join(f"{name}'s on {listing(names)}" for name, names in winners.items())
    plain = [next((c["at_budget"]["rel_mse"] for c in s["curves"] if _combo(c) == "path/independent"), None)
             / _best_at_budget(s)["at_budget"]["rel_mse"] for s in scenes
             if any(_combo(c) == "path/independent" for c in s["curves"])]
    sentence = f"Given {num(budget)} s of rendering, the lowest relMSE is {said}"
    if plain:
        sentence += f"; plain path tracing (path/independent) ends at {spread(plain, times)} that"
    section.findings.append(sentence + ".")
    mitsuba = report.get("mitsuba") or {}
    if mitsuba.get("available") and "mis/independent" in mitsuba.get("rows", {}):
        ours, theirs = mitsuba["rows"]["mis/independent"], mitsuba["rows"]["mitsuba"]
        section.findings.append(
            f"On the Cornell box, Lantern's mis reaches Mitsuba's {mitsuba['target_spp']}-spp RMSE in "
            f"{num(ours['seconds_to_target'])} s against Mitsuba's {num(theirs['seconds_to_target'])} s "
            f"({verdict(mitsuba.get('passed'))}).")
        best = mitsuba["rows"].get("mis/sobol")
        theirs_best = next(((name, r) for name, r in mitsuba["rows"].items() if name.startswith("mitsuba/")), None)
        if best is not None and theirs_best is not None:
            name, r = theirs_best
            section.findings.append(
                f"Best sampler against best: Lantern mis/sobol reaches it in {num(best['seconds_to_target'])} s "
                f"({num(best['spp_to_target'])} spp) against Mitsuba {name.split('/', 1)[1]}'s "
                f"{num(r['seconds_to_target'])} s ({num(r['spp_to_target'])} spp): "
                f"{times(r['seconds_to_target'] / best['seconds_to_target'])} Mitsuba's speed.")
    whole = report.get("whole_process") or {}
    if whole.get("available"):
        section.findings.append(
            f"As whole processes (Cornell box {whole['size']}x{whole['size']}, {whole['spp']} spp), Lantern's render "
            f"command takes {num(whole['lantern']['median_s'])} s against Mitsuba's {num(whole['mitsuba']['median_s'])} s: "
            f"{times(whole['ratio'])} (target at most {times(whole['target_ratio'])}: {verdict(whole['passed'])})."
            + (f" Of that, the render alone takes {num(whole['lantern']['render_median_s'])} s against "
               f"{num(whole['mitsuba']['render_median_s'])} s ({times(whole['render_ratio'])}), start-up and the rest "
               f"{num(whole['lantern']['outside_render_median_s'])} s against "
               f"{num(whole['mitsuba']['outside_render_median_s'])} s." if whole.get("render_ratio") else ""))
    mesh = report.get("mesh_heavy") or {}
    if mesh.get("available"):
        section.findings.append(
            f"On the mesh-heavy {mesh['scene']} scene, Lantern's best ({mesh['best_lantern']}) reaches Mitsuba's "
            f"{mesh['target_spp']}-spp error at {times(mesh['best_ratio'])} the speed of Mitsuba's best "
            f"({mesh['best_mitsuba']}) ({verdict(mesh['passed'])}).")
    return section


# --- photons -------------------------------------------------------------------------------------

def photons_section(report: dict) -> Section:
    entries = report.get("scenes", [])
    scenes = [s for s in entries if "curves" in s]
    budget = report.get("config", {}).get("budget_s")
    section = Section()
    for s in scenes:
        rows = []
        for name, c in s["curves"].items():
            raw, cor = c["at_budget"], c["at_budget_floor_corrected"]
            rows.append([name, s["compile_s"].get(name), c["spp"], raw["rel_mse"], cor["rel_mse"],
                         raw["rel_mse_caustic"], cor["rel_mse_caustic"]])
        ref = s["reference"]
        section.blocks += [
            f"**{s['scene']}** ({s['size'][0]}x{s['size'][1]}) at equal time T = {num(budget)} s; reference: mis, "
            f"{num(ref['spp'])} spp in {num(ref['seconds'])} s; caustic region {num(s['caustic_pixels'])} pixels. "
            f"Target (sppm's floor-corrected caustic relMSE below mis's): {verdict(s['target']['passed'])}.",
            table(["integrator", "first launch s", "spp / iterations", "relMSE", "relMSE −floor", "caustic relMSE",
                   "caustic −floor"], rows)]
    section.blocks += _skipped_block(entries)
    if scenes:
        parts = []
        for s in scenes:
            t = s["target"]
            ratio = f", {times(t['sppm'] / t['mis'])}" if t["mis"] and t["sppm"] else ""
            parts.append(f"{num(t['sppm'])} against mis's {num(t['mis'])} on {s['scene']}{ratio} "
                         f"({verdict(t['passed'])})")
        section.findings.append(
            f"Given {num(budget)} s, SPPM's error in the caustics (relMSE less the reference's own noise) is "
            + "; ".join(parts) + ".")
    return section


# --- denoise -------------------------------------------------------------------------------------

def _point_at(curve: list[dict], spp: int) -> dict | None:
    return next((p for p in curve if p["spp"] == spp), None)


def _paired(paired: dict | None) -> str:
    return paired_text(paired) if paired else MISSING


def _adaptive_row(scene: dict, adaptive: dict) -> list:
    """One adaptive render against the uniform render it was compared with (reports before
    renders could end early compared every one with the scene's budget)."""
    uniform = adaptive.get("uniform", scene["uniform"])
    seconds = num(uniform["seconds"]) + (" (ended early)" if adaptive.get("ended_early") else "")
    return [scene["scene"], seconds, uniform["spp"], uniform["rel_mse_corrected"], adaptive["threshold"],
            adaptive["mean_spp"], pct(adaptive["stopped_fraction"], 0), adaptive["rel_mse_corrected"],
            "yes" if adaptive["rel_mse_corrected"] < uniform["rel_mse_corrected"] else "no",
            _paired(adaptive.get("paired")), _paired(adaptive.get("paired_trimmed"))]


def denoise_section(report: dict) -> Section:
    entries = report.get("scenes", [])
    scenes = [s for s in entries if "curve" in s]
    section = Section()
    rows = []
    for s in scenes:
        t, match = s["target_denoise"], s["raw_spp_matching_denoised_8"]
        at8 = _point_at(s["curve"], 8)
        quick8 = at8.get("denoised_quick_corrected", MISSING) if at8 else MISSING
        rows.append([s["scene"], s["reference"]["spp"], at8["raw_corrected"] if at8 else MISSING, t["denoised_8"],
                     quick8, f"{num(t['raw_128'])} ({num(t['raw_spp'])} spp)",
                     num(match["spp"]) + (" (extrapolated)" if match["extrapolated"] else ""), verdict(t["passed"])])
    config = report.get("config", {})
    w, h = config.get("size", ("?", "?"))
    section.blocks += [
        f"Raw and denoised (Open Image Denoise with albedo and normal AOVs; `quick`: the AOVs not "
        f"prefiltered, the viewer's first denoise) against a long reference, mis at "
        f"{w}x{h}; relMSE less the reference's own noise. Target: denoised at 8 spp below raw at 128 spp.",
        table(["scene", "reference spp", "raw at 8 spp", "denoised at 8 spp", "quick at 8 spp", "raw at 128 spp",
               "raw spp to match denoised at 8", "target"], rows)]
    viewer = [s for s in scenes if "viewer_size" in s]
    if viewer:
        from renderer.bench.denoise import viewer_row

        vw, vh = viewer[0]["viewer_size"]["size"]
        boost = viewer[0]["viewer_size"].get("with_features_boost", "?")
        section.blocks += [
            f"The same target at the viewer's size, {vw}x{vh}, where a texture's lines and a normal map's "
            "bevels span more pixels: raw and denoised at 8 spp (the AOVs prefiltered), without feature "
            f"samples for the AOVs and with {boost} for each of the first 8 samples, and raw at 128 spp, "
            "against a reference of its own; render seconds, the denoiser's excluded. The target takes the "
            "scene's own choice (`feature samples`: only scenes with texture or normal maps take them), what "
            "`render --denoise` and the viewer's denoised view do.",
            table(["scene", "reference spp", "raw at 8 spp", "feature samples", "denoised at 8, none",
                   "denoised at 8, with", "raw at 128 spp", "render s at 8, none", "at 8, with", "at 128",
                   "target"], [viewer_row(s) for s in viewer])]
    rows = [_adaptive_row(s, a) for s in scenes for a in s["adaptive"]]
    section.blocks += [
        "Adaptive against uniform sampling at equal time (the budget: uniform sampling's time to "
        f"{num(config.get('equal_time_spp'))} spp, or the adaptive render's own time where it stopped every "
        "pixel before it, \"ended early\"; relMSE less the reference's noise; paired z: the "
        f"per-pixel difference of the two errors over its standard error, same seed, |z| > {Z_SIGNIFICANT} a "
        "difference at the 5% level; trimmed: without the 0.1% of pixels with the largest errors):",
        table(["scene", "equal time s", "uniform spp", "uniform relMSE", "threshold", "adaptive mean spp", "stopped",
               "adaptive relMSE", "adaptive better", "paired z", "paired z, trimmed"], rows)]
    frame = report.get("denoiser_frame_s")
    if isinstance(frame, (int, float)):
        fw, fh = report.get("frame_size", ("?", "?"))
        quick = report.get("denoiser_frame_quick_s")
        quick_text = f"; quick: {num(1000 * quick)} ms" if isinstance(quick, (int, float)) else ""
        section.blocks.append(f"Denoiser time per {fw}x{fh} frame: {num(1000 * frame)} ms (median of 3){quick_text}.")
    section.blocks += _skipped_block(entries)
    if scenes:
        passed = sum(s["target_denoise"]["passed"] for s in scenes)
        matched = spread([s["raw_spp_matching_denoised_8"]["spp"] for s in scenes])
        sentence = (f"Denoising 8 spp gives the error of {matched} spp of raw rendering ({passed} of {len(scenes)} "
                    f"scenes below raw at 128 spp at {w}x{h}")
        if viewer:
            sentence += (f"; {sum(s['viewer_size']['passed'] for s in viewer)} of {len(viewer)} at the viewer's "
                         f"{vw}x{vh}")
        sentence += ")"
        if isinstance(frame, (int, float)):
            sentence += f", for {num(1000 * frame)} ms of denoising per {fw}x{fh} frame"
        section.findings.append(sentence + ".")
        wins = [s for s in scenes if s["target_adaptive"]["passed"]]
        ratios = [s["target_adaptive"]["adaptive"] / s["target_adaptive"]["uniform"] for s in scenes
                  if s["target_adaptive"]["uniform"]]
        paired = [s["target_adaptive"].get("paired_trimmed") for s in scenes]
        paired_sentence = ""
        if all(paired):
            paired_sentence = (f" (a paired z-test without the 0.1% largest errors: better on {paired.count('better')}, "
                               f"worse on {paired.count('worse')}, no significant difference on {paired.count('tie')})")
        section.findings.append(
            f"Adaptive sampling (threshold {num(scenes[0]['target_adaptive']['threshold'])}) ends below uniform "
            f"sampling at equal time on {len(wins)} of {len(scenes)} scenes, at {spread(ratios, times)} its "
            f"error{paired_sentence}.")
    return section

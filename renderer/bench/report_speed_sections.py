"""The benchmark page's sections of the speed benchmarks (startup, bvh, features, interactive): their
main tables rendered from the JSON reports, and what each knob costs, in words computed from the
same figures. The key names are those renderer/bench/startup.py, bvh_measure.py + bvh.py,
features.py and interactive.py write."""
from __future__ import annotations

from renderer.bench.report_markdown import (
    MISSING,
    Section,
    details,
    interval,
    is_number,
    num,
    pct,
    spread,
    table,
    times,
    verdict,
)

# --- startup -------------------------------------------------------------------------------------


def _label(entry: dict) -> str:
    return f"{entry['mode']}, kernels for {entry.get('optimize', 'compile')}"


def startup_section(report: dict) -> Section:
    section = Section()
    measurements = report.get("measurements", [])
    rows = []
    for m in measurements:
        cold, warm = m["cold"], m["warm"]
        rows.append([_label(m), cold.get("start_to_first_frame"), warm.get("start_to_first_frame"),
                     warm.get("import_and_init"), warm.get("start_to_first_window_frame"), warm.get("moving_ms"),
                     m.get("cache_bytes", 0) / 1e6, f"{warm.get('ok', 0)} of {warm.get('runs', 0)}"])
    w, h = report.get("size", ("?", "?"))
    section.blocks += [
        f"Seconds from process start ({report.get('scene', '?')}, {w}x{h}, CPU). Cold: an empty kernel cache; "
        f"warm: the median of the runs on the filled cache. The viewer's first frame is the first step() that "
        f"shows a rendered image; moving: the median frame with W held.",
        table(["measurement", "cold: to first frame", "warm: to first frame", "warm: import + init",
               "warm: to first window frame", "moving frame ms", "kernel cache MB", "warm runs ok"], rows)]
    levels = report.get("optimization_levels", [])
    if levels:
        section.blocks += [
            "Kernel optimisation levels (renderer; kernels = first frame − next frame):",
            table(["optimise for", "cold kernels s", "warm kernels s", "1 spp frame s", "Msamples/s"],
                  [[lv["optimize"], lv.get("cold_kernels"), lv.get("warm_kernels"), lv.get("frame_seconds"),
                    lv.get("msamples_per_second")] for lv in levels])]
    target_rows = []
    for t in report.get("targets", []):
        if "moving_ms" in t:
            target_rows.append([t["what"], "frame while moving", f"{num(t['moving_ms'])} ms", "≤ 50 ms",
                                verdict(t["passed"])])
        else:
            target_rows.append([t["what"], "warm start to first frame", f"{num(t['seconds'])} s",
                                f"≤ {num(report.get('target_seconds'))} s",
                                verdict(t["passed"]) if t.get("judged", True) else "reported"])
    if target_rows:
        section.blocks.append(table(["what", "measure", "value", "target", "verdict"], target_rows))
    phase_rows = []
    for m in measurements:
        for name in m["cold"].get("phases", {}):
            phase_rows.append([_label(m), name, m["cold"]["phases"][name], m["warm"].get("phases", {}).get(name)])
    if phase_rows:
        section.blocks.append(details("Every phase (cold, warm median), seconds",
                                      table(["measurement", "phase", "cold", "warm"], phase_rows)))
    if report.get("viewer_note"):
        section.blocks.append(report["viewer_note"])

    judged = next((t for t in report.get("targets", []) if "seconds" in t and t.get("judged", True)), None)
    if judged is not None:
        entry = next((m for m in measurements if m["mode"] == judged["mode"]), None)
        cold = entry["cold"].get("start_to_first_frame") if entry else None
        section.findings.append(
            f"A warm start ({judged['what']}) takes {num(judged['seconds'])} s (target ≤ "
            f"{num(report.get('target_seconds'))} s: {verdict(judged['passed'])}); a cold one, compiling every "
            f"kernel, {num(cold)} s.")
    by_level = {lv["optimize"]: lv for lv in levels}
    fast, quick = by_level.get("run"), by_level.get("compile")
    if fast and quick and all(is_number(lv.get(k)) for lv in (fast, quick)
                              for k in ("cold_kernels", "msamples_per_second")):
        section.findings.append(
            f"Kernels optimised for speed (`--optimize run`) take {num(fast['cold_kernels'])} s to compile cold "
            f"against {num(quick['cold_kernels'])} s for `compile`, and render "
            f"{times(fast['msamples_per_second'] / quick['msamples_per_second'])} as many samples per second.")
    return section


# --- bvh -----------------------------------------------------------------------------------------

def _config(c: dict) -> str:
    return f"{c['strategy']}/{c['traversal']}/{c['triangle_test']}"


def _bvh_trace_details(mesh: dict) -> str:
    rows = [[_config(c), c["compile_s"], c["coherent"]["mrays_per_s"], c["coherent"]["nodes_per_ray"],
             c["incoherent"]["mrays_per_s"], c["incoherent"]["nodes_per_ray"], c["incoherent"]["tests_per_ray"],
             pct(c["incoherent"].get("agreement", {}).get("fraction"), 3)] for c in mesh["configs"]]
    e = mesh.get("embree", {})
    if e.get("available"):
        rows.append(["embree", MISSING, e["coherent"]["mrays_per_s"], MISSING, e["incoherent"]["mrays_per_s"],
                     MISSING, MISSING, MISSING])
    return details(f"{mesh['name']}: every split strategy × traversal × triangle test",
                   table(["configuration", "first call s", "coherent Mrays/s", "nodes/ray", "incoherent Mrays/s",
                          "nodes/ray", "tests/ray", "agrees with Embree"], rows))


def _same_traversal(mesh: dict, strategy: str, scalar_leaves: bool = False) -> dict | None:
    """The configuration of `strategy` with the default configuration's traversal and triangle test
    (with scalar leaves: packet leaves are measured on the sah trees only)."""
    default = mesh["default_config"].split("/")
    if scalar_leaves:
        default[1] = default[1].split("+")[0]
    return next((c for c in mesh["configs"]
                 if [c["strategy"], c["traversal"], c["triangle_test"]] == [strategy, *default[1:]]), None)


def bvh_section(report: dict) -> Section:
    section = Section()
    meshes = report.get("meshes", [])
    embree = report.get("embree", {})
    targets = report.get("targets", {})
    rows = []
    for m in meshes:
        for b in m["builds"]:
            rows.append([m["name"], m["triangles"], b["strategy"], b["seconds"], b["triangles_per_s"] / 1e6,
                         b["sah_cost"], b["depth"], b["device_bytes"]["per_triangle"]])
        if m.get("embree", {}).get("available"):
            rows.append([m["name"], m["triangles"], "embree (commit)", m["embree"]["build_s"],
                         m["triangles"] / m["embree"]["build_s"] / 1e6, MISSING, MISSING, MISSING])
    bytes_ok = targets.get("bytes_per_triangle_passed", {})
    big_build = targets.get("sah_build_1m")
    big_said = f"{verdict(big_build['passed'])}: {num(big_build['seconds'])} s" if big_build else "not measured"
    packet_leaf = next((b["packet_tree"]["max_leaf_size"] for m in meshes for b in m["builds"] if "packet_tree" in b),
                       None)
    leaves = f"leaves of at most 4, {packet_leaf} for the packet configurations" if packet_leaf else "leaves of at most 4"
    section.blocks += [
        f"Builds ({leaves}; median of repeats). Targets: ≤ {num(targets.get('bytes_per_triangle'))} "
        f"device bytes per triangle with SAH ({verdict(all(bytes_ok.values()) if bytes_ok else None)}) and the SAH "
        f"build of the 1M mesh in ≤ {num(targets.get('sah_build_seconds'))} s ({big_said}).",
        table(["mesh", "triangles", "strategy", "build s", "Mtriangles/s", "SAH cost", "depth", "bytes/triangle"],
              rows)]
    layouts = [(m, b["device_bytes_by_traversal"]) for m in meshes for b in m["builds"]
               if b["strategy"] == "sah" and "device_bytes_by_traversal" in b]
    if layouts:
        names = list(layouts[0][1])
        section.blocks += [
            "Device bytes per triangle (BVH and intersection data) of each traversal and leaf layout on the SAH "
            f"tree (the Renderer's: {meshes[0]['default_config'].split('/')[1]}):",
            table(["mesh", *names], [[m["name"], *(by.get(n, {}).get("per_triangle") for n in names)]
                                     for m, by in layouts])]
    rows = []
    for m in meshes:
        default = next(c for c in m["configs"] if _config(c) == m["default_config"])
        best = next(c for c in m["configs"] if _config(c) == m["best_incoherent_config"])
        e = m.get("embree", {})
        ratio = m.get("ratio_to_embree", {}).get("incoherent", {}).get("default")
        rows.append([m["name"], default["coherent"]["mrays_per_s"], default["incoherent"]["mrays_per_s"],
                     f"{m['best_incoherent_config']} ({num(best['incoherent']['mrays_per_s'])})",
                     e["incoherent"]["mrays_per_s"] if e.get("available") else MISSING, times(ratio),
                     pct(m.get("agreement_all_configs", {}).get("incoherent"), 3)])
    version = " ".join(str(embree.get("version", "")).split())  # embreex's own text: "Embree version: 4.4.0 (...)"
    embree_note = ((version if version.startswith("Embree") else f"Embree {version}".strip()) if embree.get("available")
                   else f"Embree not measured ({embree.get('note', 'unavailable')})")
    section.blocks += [
        f"Closest-hit rays, Mrays/s, with the Renderer's configuration "
        f"({meshes[0]['default_config'] if meshes else ''}) and the fastest one on incoherent rays; {embree_note}; "
        f"target ≥ {num(targets.get('embree_ratio'))}x Embree on incoherent rays.",
        table(["mesh", "coherent", "incoherent", "fastest incoherent", "Embree incoherent", "vs Embree",
               "all agree with Embree"], rows)]
    section.blocks += [_bvh_trace_details(m) for m in meshes]
    wide_rows = [[m["name"], f"{w['strategy']}/{w.get('traversal', 'wide4')}/{w['triangle_test']}",
                  times(w["coherent"]["speedup"]),
                  times(w["incoherent"]["speedup"]),
                  f"{num(w['incoherent']['wide_nodes_per_ray'])} / {num(w['incoherent']['binary_nodes_per_ray'])}"]
                 for m in meshes for w in m.get("wide_vs_binary", [])]
    if wide_rows:
        section.blocks += [
            "The wide BVHs (traversals `wide4`, `wide8`) against the binary tree's `stack` traversal, rays/s of the "
            "same interleaved runs (a wide node visit tests four or eight boxes):",
            table(["mesh", "strategy/traversal/test", "coherent", "incoherent",
                   "incoherent node visits, wide / binary"], wide_rows)]
    packet_rows = [[m["name"], f"{w['strategy']}/{w['traversal']}/{w['triangle_test']}", times(w["coherent"]["speedup"]),
                    times(w["incoherent"]["speedup"])]
                   for m in meshes for w in m.get("packets_vs_scalar", [])]
    if packet_rows:
        section.blocks += [
            "Packet leaves (`+packets`: four slots tested at a time, triangles structure-of-arrays) against the "
            "scalar leaves on the same tree, rays/s of the same interleaved runs:",
            table(["mesh", "strategy/traversal/test", "coherent", "incoherent"], packet_rows)]
    shadow = [m for m in meshes if "shadow" in m]
    if shadow:
        section.blocks.append(details("Shadow rays: any-hit against closest-hit on the same segments", table(
            ["mesh", "any-hit Mrays/s", "closest-hit Mrays/s", "speed-up", "occluded", "Embree any-hit Mrays/s"],
            [[m["name"], m["shadow"]["occluded_mrays_per_s"], m["shadow"]["closest_mrays_per_s"],
              times(m["shadow"]["occluded_mrays_per_s"] / m["shadow"]["closest_mrays_per_s"]),
              pct(m["shadow"]["occluded_fraction"]), m["shadow"].get("embree_occluded_mrays_per_s", MISSING)]
             for m in shadow])))
    leaf = report.get("leaf_size")
    if leaf:
        section.blocks += [
            f"Leaf size, SAH on {leaf['mesh']} ({num(leaf['triangles'])} triangles), {leaf['config']}, "
            f"{num(leaf['rays'])} incoherent rays (* = the Renderer's default):",
            table(["max leaf", "build s", "SAH cost", "bytes/triangle", "incoherent Mrays/s", "nodes/ray", "tests/ray"],
                  [[("*" if r["max_leaf_size"] == leaf["renderer_default"] else "") + str(r["max_leaf_size"]),
                    r["build_s"], r["sah_cost"], r["device_bytes"]["per_triangle"], r["incoherent"]["mrays_per_s"],
                    r["incoherent"]["nodes_per_ray"], r["incoherent"]["tests_per_ray"]] for r in leaf["rows"]])]

    if meshes:
        big = max(meshes, key=lambda m: m["triangles"])
        builds = {b["strategy"]: b for b in big["builds"]}
        sah, mid = _same_traversal(big, "sah"), _same_traversal(big, "midpoint")
        if mid is None:  # the default's leaf layout was measured on sah only: compare scalar leaves
            sah, mid = _same_traversal(big, "sah", True), _same_traversal(big, "midpoint", True)
        if "sah" in builds and "midpoint" in builds and sah and mid:
            slower = builds["sah"]["seconds"] / builds["midpoint"]["seconds"]
            sentence = (f"On {big['name']} ({num(big['triangles'])} triangles) the SAH build takes "
                        f"{num(builds['sah']['seconds'])} s, {times(slower)} the midpoint split's, and its tree traces "
                        f"incoherent rays "
                        f"{times(sah['incoherent']['mrays_per_s'] / mid['incoherent']['mrays_per_s'])} as fast")
            ratio = big.get("ratio_to_embree", {}).get("incoherent", {}).get("default")
            if ratio is not None:
                target = targets["embree_ratio"]
                passed = [ok for ok in targets.get("embree_ratio_passed", {}).values() if ok is not None]
                big_target = targets.get("embree_ratio_1m")
                sentence += (f"; the Renderer's configuration runs at {times(ratio)} Embree's incoherent rays/s "
                             f"(target {num(target)}x on every mesh: met on {sum(passed)} of {len(passed)}"
                             + (f"; {num(big_target['target'])}x on this one: {verdict(big_target['passed'])}"
                                if big_target else "") + ")")
            wide = next((w for w in big.get("wide_vs_binary", []) if w["strategy"] == "sah"
                         and f"sah/stack/{w['triangle_test']}" == big["default_config"]), None)
            if wide is not None:
                sentence += (f"; its 4-wide traversal runs at {times(wide['incoherent']['speedup'])} the binary "
                             f"stack traversal's incoherent rays/s")
            base = big["default_config"].split("/")
            packed = next((w for w in big.get("packets_vs_scalar", []) if base[1] == f"{w['traversal']}+packets"
                           and [w["strategy"], w["triangle_test"]] == [base[0], base[2]]), None)
            if packed is not None:
                sentence += (f"; its packet leaves run at {times(packed['incoherent']['speedup'])} the scalar "
                             f"leaves' incoherent rays/s ({times(packed['coherent']['speedup'])} coherent)")
            section.findings.append(sentence + ".")
    if leaf:
        default = next((r for r in leaf["rows"] if r["max_leaf_size"] == leaf["renderer_default"]), None)
        sentence = (f"Leaves of at most {leaf['best_max_leaf_size']} trace fastest on {leaf['mesh']} (within "
                    f"{pct(leaf['tie_fraction'], 0)}: {', '.join(str(v) for v in leaf['within_tie_of_best'])})")
        if default:
            sentence += (f"; the default {leaf['renderer_default']} takes "
                         f"{num(default['device_bytes']['per_triangle'])} device bytes per triangle")
        section.findings.append(sentence + ".")
    return section


# --- features ------------------------------------------------------------------------------------

def features_section(report: dict) -> Section:
    section = Section()
    entries = report.get("scenes", [])
    scenes = [s for s in entries if "builds" in s and "error" not in s]
    summary = report.get("summary", {})
    config = report.get("config", {})
    compile_word = "cold compile" if config.get("fresh_cache", True) else "first call"
    rows = []
    for s in scenes:
        own, every = s["builds"]["own"], s["builds"].get("everything", {})
        rows.append([s["scene"], s["geometry"], own.get("compile_s"), every.get("compile_s"),
                     own.get("samples_per_s", 0) / 1e6, interval(every.get("vs_own"))])
    section.blocks += [
        f"The scene's own kernels against every optional effect compiled in ({report.get('integrator', 'mis')}, "
        f"{'x'.join(str(v) for v in config.get('size', ()))}; median of paired passes with its 95 % interval):",
        table(["scene", "geometry", f"{compile_word} own s", "all effects s", "Msamples/s own",
               "t(all) / t(own)"], rows)]
    by_effect: dict[str, list[dict]] = {}
    for v in summary.get("unused_effects", []):
        by_effect.setdefault(v["effect"], []).append(v)
    rows = [[effect.removeprefix("has_"), len(vs), spread([v.get("ratio") for v in vs], lambda x: f"{x:.3f}"),
             f"{sum(v['passed'] for v in vs)} of {len(vs)}"] for effect, vs in by_effect.items()]
    if rows:
        section.blocks += [
            f"One unused effect forced on at a time: t(own + effect) / t(own) over the scenes; an effect fails where "
            f"the own build is measurably faster (95 % interval wholly below {1 - summary.get('tolerance', 0):.2f}). "
            f"Target: {verdict(summary.get('passed'))}.",
            table(["unused effect", "scenes", "ratio range", "pass"], rows)]
    rows = []
    for s in scenes:
        for c in s.get("cases", []):
            if "ratio" in c:
                rows.append([c["effect"], s["scene"], c["without"], interval(c["ratio"]), c["image_difference"],
                             c["noise_floor"], pct(c["mean_change"], signed=True)])
    if rows:
        section.blocks += [
            "What each effect costs where a scene uses it (images: sum |with − without| / sum without at equal spp, "
            "against the same between two renders with it):",
            table(["effect", "scene", "without it", "t(with) / t(without)", "image difference", "noise floor",
                   "mean change"], rows)]
    section.blocks += [f"Not measured: {s['scene']}: {s['error']}." for s in entries if "error" in s]

    slower = [s["builds"]["everything"]["vs_own"]["median"] - 1.0 for s in scenes
              if "vs_own" in s["builds"].get("everything", {})]
    verdicts = summary.get("unused_effects", [])
    if slower:
        section.findings.append(
            f"Compiling every optional effect in changes a scene's time per sample by "
            f"{spread(slower, lambda x: pct(x, signed=True))}; {sum(v['passed'] for v in verdicts)} of {len(verdicts)} "
            f"unused effects cost nothing measurable (target: {verdict(summary.get('passed'))}).")
    cases = [(c["ratio"]["median"], c["effect"], s["scene"]) for s in scenes for c in s.get("cases", [])
             if "ratio" in c]
    if cases:
        ratio, effect, scene = max(cases)
        sentence = f"Where a scene uses it, {effect} costs the most: {times(ratio)} the time per sample on {scene}"
        if len(cases) > 1:
            low, cheap, where = min(cases)
            sentence += f"; {cheap} the least, {times(low)} on {where}"
        section.findings.append(sentence + ".")
    return section


# --- interactive ---------------------------------------------------------------------------------

def _first_round_ratio(result: dict):
    """The first round's samples/s against whole-sample frames; None where it was not measured."""
    first = result["still"].get("first_round")
    return None if first is None else first["rate_ratio"]


def _moving_share(result: dict) -> str:
    share = result["moving"].get("pixel_share_median")  # reports from before it was measured have none
    return "-" if share is None else pct(share, 1)


def interactive_section(report: dict) -> Section:
    section = Section()
    results = report.get("results", [])
    measured = [r for r in results if "skipped" not in r]
    target = report.get("latency_target_ms")
    rows = [[r["scene"], r["integrator"], r["latency_p50_ms"], r["latency_p95_ms"], r["whole_samples_p95_ms"],
             r["still"]["samples_per_s"] / 1e6, times(r["still"]["rate_ratio"], 3),
             "-" if _first_round_ratio(r) is None else times(_first_round_ratio(r), 3),
             r["still"]["frame_ms_median"],
             r["moving"]["frame_ms_median"], _moving_share(r), r["switch"]["first_image_s"]] for r in measured]
    w, h = report.get("config", {}).get("size", ("?", "?"))
    packets = report.get("config", {}).get("packets")
    rays = f", {packets} rays a packet where a scene allows (`view --packets {packets}`)" if packets else ""
    section.blocks += [
        f"Input latency (event to presented frame), viewer off-screen at {w}x{h}{rays}: target p95 ≤ {num(target)} ms "
        f"({verdict(report.get('latency_ok'))}); still samples/s of sliced frames against whole-sample frames (the "
        f"median over pairs of blocks of equal time, after the view's first round) ≥ "
        f"{pct(report.get('still_rate_target'), 0)} ({verdict(report.get('rate_ok'))}).",
        table(["scene", "integrator", "p50 ms", "p95 ms", "p95 ms, whole-sample frames", "still Msamples/s",
               "vs whole-sample frames", "first round vs whole-sample frames", "still frame ms", "moving frame ms",
               "moving film (share of the window)", "switch s"], rows)]
    skipped = [f"{r['scene']} / {r['integrator']}: {r['skipped']}" for r in results if "skipped" in r]
    if skipped:
        section.blocks.append("Not measured: " + "; ".join(skipped) + ".")
    if measured:
        worst = max(measured, key=lambda r: r["latency_p95_ms"])
        ratios = [r["still"]["rate_ratio"] for r in measured if r["integrator"] != "sppm"]
        sentence = (f"The p95 input latency is {spread([r['latency_p95_ms'] for r in measured])} ms (worst "
                    f"{worst['scene']} / {worst['integrator']}; target ≤ {num(target)} ms: "
                    f"{verdict(report.get('latency_ok'))})")
        if ratios:
            sentence += (f", and cutting still frames into pixel slices keeps {spread(ratios, pct)} of the samples "
                         f"per second of whole-sample frames")
            firsts = [_first_round_ratio(r) for r in measured
                      if r["integrator"] != "sppm" and _first_round_ratio(r) is not None]
            if firsts:
                sentence += f" after a view's first round ({spread(firsts, pct)} during it, its slices interleaved)"
        section.findings.append(sentence + ".")
    return section

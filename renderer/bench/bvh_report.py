"""The BVH benchmark's report: tables on stdout and PNG plots of its measurements
(renderer.bench.bvh_measure)."""
import os
from pathlib import Path

import numpy as np

from renderer.bench import embree_side
from renderer.bench.bvh_measure import (
    BYTES_PER_TRIANGLE_TARGET,
    DEFAULT_LEAF,
    PACKET_LEAF,
    EMBREE_RATIO_TARGET,
    SAH_BUILD_TARGET_S,
    config_name,
)
from renderer.bench.common import print_table, pyplot, save_figure, verdict


def _pct(x) -> str:
    return "-" if x is None else f"{100 * x:.3f}%"


def _print_discrepancies(m: dict) -> None:
    """One line per distinct disagreement with Embree, naming the configurations that show it."""
    groups = {}
    for c in m["configs"]:
        for kind in ("coherent", "incoherent"):
            a = c[kind].get("agreement")
            if a and a["disagreeing"]:
                key = (kind, a["disagreeing"], a["lantern_only_hits"], a["embree_only_hits"],
                       a["distance_mismatches"], f"{a['max_relative_difference']:.2g}", a["rays"])
                groups.setdefault(key, []).append(c)
    n_per_test = len({(c["strategy"], c["traversal"]) for c in m["configs"]})
    for (kind, bad, l_only, e_only, far, rel, rays), configs in groups.items():
        tests = {c["triangle_test"] for c in configs}
        if len(tests) == 1 and len(configs) == n_per_test and n_per_test > 1:
            who = f"all {len(configs)} {tests.pop()} configurations alike"
        else:
            who = ", ".join(config_name(c["strategy"], c["traversal"], c["triangle_test"]) for c in configs)
        print(f"    differs from Embree on {kind} rays: {bad} of {rays:,} (hit only by Lantern {l_only}, only by "
              f"Embree {e_only}, distance beyond {embree_side.AGREEMENT_RTOL:g} {far}; largest relative distance difference "
              f"{rel}): {who}")


def print_report(report: dict) -> None:
    meshes = report["meshes"]
    th = report["threads"]
    print(f"Threads: Taichi CPU kernels {th['taichi']}; BVH builder (numpy) {th['bvh_builder']}; "
          f"Embree rays {th['embree_trace']} (Python threads over chunks), Embree build: its own pool over "
          f"{th['embree_build']} cores.  Embree: "
          f"{report['embree']['version'] if report['embree']['available'] else 'n/a'}")
    la = report["load_average"]
    print(f"Load average (1, 5, 15 min) before {la['before']}, after {la['after']}, on {os.cpu_count()} cores: "
          f"timings are only as quiet as the machine.")
    print()
    rows = []
    for m in meshes:
        for b in m["builds"]:
            db = b["device_bytes"]
            rows.append([m["name"], m["triangles"], b["strategy"], b["seconds"], b["triangles_per_s"] / 1e6,
                         b["sah_cost"], b["nodes"], b["depth"], b["mean_leaf_size"], db["bvh_per_triangle"],
                         db["per_triangle"], verdict(db["target_passed"])])
        if m["embree"].get("available"):
            rows.append([m["name"], m["triangles"], "embree", m["embree"]["build_s"],
                         m["triangles"] / m["embree"]["build_s"] / 1e6, "-", "-", "-", "-", "-", "-", ""])
    print_table(["mesh", "tris", "strategy", "build s", "Mtris/s", "SAH cost", "nodes", "depth", "leaf avg",
                 "B/tri bvh", "B/tri all", f"<= {BYTES_PER_TRIANGLE_TARGET:g} B"], rows,
                title=f"BVH build (median of {report['config']['build_runs']} builds, "
                      f"{report['config']['build_runs_large']} for 1M; max_leaf_size {DEFAULT_LEAF}, and "
                      f"{PACKET_LEAF} for the +packets configurations' trees; boxes and "
                      f"centroids prepared beforehand; embree = scene commit)")
    for m in meshes:
        print(f"  {m['name']}: per-triangle boxes + centroids {m['bounds_s']:.3f} s (not in the build times)")
    print()

    for m in meshes:
        rows = []
        for c in m["configs"]:
            co, inc = c["coherent"], c["incoherent"]
            rows.append([config_name(c["strategy"], c["traversal"], c["triangle_test"]), c["compile_s"],
                         co["mrays_per_s"], co["nodes_per_ray"], co["tests_per_ray"],
                         _pct(co.get("agreement", {}).get("fraction")),
                         inc["mrays_per_s"], inc["nodes_per_ray"], inc["tests_per_ray"],
                         _pct(inc.get("agreement", {}).get("fraction"))])
        e = m["embree"]
        if e.get("available"):
            rows.append(["embree", "-", e["coherent"]["mrays_per_s"], "-", "-", "",
                         e["incoherent"]["mrays_per_s"], "-", "-", ""])
        r = m["rays"]
        hits = {kind: m["configs"][0][kind]["hit_fraction"] for kind in ("coherent", "incoherent")}
        print_table(["config", "1st call s", "coh Mray/s", "nodes", "tests", "=embree",
                     "incoh Mray/s", "nodes", "tests", "=embree"], rows,
                    title=f"Closest-hit traversal, {m['name']} ({m['triangles']:,} triangles): coherent = "
                          f"{r['coherent']['camera'][0]}x{r['coherent']['camera'][1]} camera rays "
                          f"({hits['coherent']:.0%} hit), incoherent = {r['incoherent']['count']:,} random rays "
                          f"({hits['incoherent']:.0%} hit); nodes/tests = mean per ray; =embree = rays agreeing "
                          f"with Embree (same miss, or t within {embree_side.AGREEMENT_RTOL:g} relative); 1st call = compile "
                          f"(or load from Taichi's offline cache) + 64 rays")
        for w in m.get("packets_vs_scalar", ()):
            co, inc = w["coherent"], w["incoherent"]
            print(f"  packet / scalar leaves ({w['strategy']}, {w['traversal']}, {w['triangle_test']}): coherent "
                  f"{co['speedup']:.2f}x (fastest runs {co['speedup_fastest_runs']:.2f}x), incoherent "
                  f"{inc['speedup']:.2f}x (fastest runs {inc['speedup_fastest_runs']:.2f}x)")
        for w in m.get("wide_vs_binary", ()):
            co, inc = w["coherent"], w["incoherent"]
            print(f"  {w.get('traversal', 'wide4')} / stack ({w['strategy']}, {w['triangle_test']}): coherent "
                  f"{co['speedup']:.2f}x "
                  f"(fastest runs {co['speedup_fastest_runs']:.2f}x; nodes {co['wide_nodes_per_ray']:.1f} vs "
                  f"{co['binary_nodes_per_ray']:.1f}), incoherent {inc['speedup']:.2f}x (fastest runs "
                  f"{inc['speedup_fastest_runs']:.2f}x; nodes {inc['wide_nodes_per_ray']:.1f} vs "
                  f"{inc['binary_nodes_per_ray']:.1f})")
        if e.get("available"):
            ratio = m["ratio_to_embree"]
            print(f"  Lantern/Embree on {m['name']}: incoherent {ratio['incoherent']['default']:.3f}x "
                  f"({m['default_config']}; fastest runs {ratio['incoherent']['default_fastest_runs']:.3f}x), "
                  f"best config {ratio['incoherent']['best']:.3f}x ({m['best_incoherent_config']}); "
                  f"coherent {ratio['coherent']['default']:.3f}x, best config {ratio['coherent']['best']:.3f}x")
            agr = m["agreement_all_configs"]
            print(f"  rays on which all {len(m['configs'])} configurations agree with Embree: coherent "
                  f"{_pct(agr['coherent'])}, incoherent {_pct(agr['incoherent'])}")
            _print_discrepancies(m)
        print()

    shadow = [m for m in meshes if "shadow" in m]
    if shadow:
        rows = []
        for m in shadow:
            s = m["shadow"]
            rows.append([m["name"], s["config"], s["occluded_mrays_per_s"], s["closest_mrays_per_s"],
                         s["occluded_mrays_per_s"] / s["closest_mrays_per_s"], _pct(s["occluded_fraction"]),
                         _pct(s["consistent_with_closest"]), s["other"]["config"] if "other" in s else "-",
                         s["other"]["occluded_mrays_per_s"] if "other" in s else "-",
                         s.get("embree_occluded_mrays_per_s", "-"), _pct(s.get("agreement_with_embree"))])
        print_table(["mesh", "config", "any-hit Mray/s", "closest Mray/s", "speed-up", "occluded",
                     "=closest", "other tree", "its any-hit Mray/s", "embree any Mray/s", "=embree"], rows,
                    title="Shadow rays (the incoherent rays as segments ending at their random targets): any-hit "
                          "(occluded) vs closest-hit on the same segments")

    leaf = report.get("leaf_size")
    if leaf:
        rows = []
        for r in leaf["rows"]:
            inc = r["incoherent"]
            rows.append([("*" if r["max_leaf_size"] == leaf["renderer_default"] else "") + str(r["max_leaf_size"]),
                         r["build_s"],
                         r["nodes"], r["mean_leaf_size"], r["largest_leaf"], r["depth"], r["sah_cost"],
                         r["device_bytes"]["per_triangle"], inc["mrays_per_s"], inc["nodes_per_ray"],
                         inc["tests_per_ray"]])
        print_table(["max leaf", "build s", "nodes", "leaf avg", "largest", "depth", "SAH cost", "B/tri",
                     "incoh Mray/s", "nodes", "tests"], rows,
                    title=f"Leaf size, SAH on {leaf['mesh']} ({leaf['triangles']:,} triangles), "
                          f"{leaf['config']}, {leaf['rays']:,} incoherent rays (* = Renderer default)")
        print(f"  best max_leaf_size by incoherent rays/s: {leaf['best_max_leaf_size']} "
              f"(Renderer default {leaf['renderer_default']}); within {leaf['tie_fraction']:.0%} of the best: "
              f"{', '.join(str(v) for v in leaf['within_tie_of_best'])}")
        print()

    t = report["targets"]
    print("Targets:")
    for m in meshes:
        b = next((b for b in m["builds"] if b["strategy"] == "sah"), None)
        if b is not None:
            db = b["device_bytes"]
            print(f"  bytes/triangle on the device (sah, leaf {DEFAULT_LEAF}), {m['name']}: {db['per_triangle']:.1f} "
                  f"(BVH {db['bvh_per_triangle']:.1f} + triangles {db['triangles'] / m['triangles']:.1f}) "
                  f"<= {BYTES_PER_TRIANGLE_TARGET:g}: {verdict(db['target_passed'])}")
    sb = t.get("sah_build_1m")
    if sb:
        print(f"  SAH build of {sb['triangles']:,} triangles: {sb['seconds']:.3f} s <= {SAH_BUILD_TARGET_S:g} s: "
              f"{verdict(sb['passed'])}")
    else:
        print("  SAH build of 1M triangles: not measured (no mesh that large)")
    if report["embree"]["available"]:
        for m in meshes:
            if "ratio_to_embree" in m:
                r = m["ratio_to_embree"]["incoherent"]["default"]
                print(f"  incoherent closest-hit vs Embree, {m['name']} ({m['default_config']}): {r:.3f}x "
                      f">= {EMBREE_RATIO_TARGET:g}x: {verdict(r >= EMBREE_RATIO_TARGET)}")
        big = t.get("embree_ratio_1m")
        if big:
            print(f"  incoherent closest-hit vs Embree on {big['mesh']}: {big['ratio']:.3f}x >= {big['target']:g}x: "
                  f"{verdict(big['passed'])}")
    else:
        print(f"  incoherent closest-hit vs Embree: not measured ({report['embree']['note']})")
    print(flush=True)


def write_plots(report: dict, out_dir: Path) -> list[Path]:
    plt = pyplot()
    written = []
    meshes = report["meshes"]
    strategies = [b["strategy"] for b in meshes[0]["builds"]] if meshes else []

    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    x = np.arange(len(meshes))
    width = 0.8 / (len(strategies) + 1)
    for i, s in enumerate(strategies):
        rows = [next(b for b in m["builds"] if b["strategy"] == s) for m in meshes]
        axes[0].bar(x + i * width, [r["seconds"] for r in rows], width, label=s)
        axes[1].bar(x + i * width, [r["sah_cost"] for r in rows], width, label=s)
        axes[2].bar(x + i * width, [r["device_bytes"]["per_triangle"] for r in rows], width, label=s)
    if report["embree"]["available"]:
        axes[0].bar(x + len(strategies) * width, [m["embree"].get("build_s", 0.0) for m in meshes], width,
                    label="embree (commit)", color="grey")
    axes[0].axhline(SAH_BUILD_TARGET_S, color="red", ls="--", lw=1, label="target: 1M SAH <= 2 s")
    axes[0].set_yscale("log")
    axes[0].set_ylabel("build seconds (median)")
    axes[1].set_ylabel("SAH cost (C_trav 1, C_isect 2)")
    axes[2].axhline(BYTES_PER_TRIANGLE_TARGET, color="red", ls="--", lw=1, label="target <= 64")
    axes[2].set_ylabel("device bytes per triangle (BVH + triangles)")
    axes[2].set_ylim(0, 1.4 * BYTES_PER_TRIANGLE_TARGET)
    for ax in axes:
        ax.set_xticks(x + width * len(strategies) / 2)
        ax.set_xticklabels([f"{m['name']}\n{m['triangles']:,}" for m in meshes], fontsize=8)
        ax.grid(True, axis="y", alpha=0.3)
        ax.legend(fontsize=7, ncol=2 if ax is axes[2] else 1)
    axes[0].set_title("BVH build time")
    axes[1].set_title("tree quality")
    axes[2].set_title("memory")
    written.append(save_figure(fig, out_dir / "bench_bvh_build.png"))

    if meshes:
        fig, axes = plt.subplots(2, len(meshes), figsize=(5 * len(meshes), 8), squeeze=False)
        for col, m in enumerate(meshes):
            for row, kind in enumerate(("coherent", "incoherent")):
                ax = axes[row, col]
                labels = [config_name(c["strategy"], c["traversal"], c["triangle_test"]) for c in m["configs"]]
                values = [c[kind]["mrays_per_s"] for c in m["configs"]]
                colors = ["C0" if lab == m["default_config"] else "C1" for lab in labels]
                if m["embree"].get("available"):
                    labels.append("embree")
                    values.append(m["embree"][kind]["mrays_per_s"])
                    colors.append("grey")
                y = np.arange(len(labels))
                ax.barh(y, values, color=colors)
                ax.set_yticks(y)
                ax.set_yticklabels(labels, fontsize=7)
                ax.invert_yaxis()
                if kind == "incoherent" and m["embree"].get("available"):
                    ax.axvline(EMBREE_RATIO_TARGET * m["embree"][kind]["mrays_per_s"], color="red", ls="--", lw=1,
                               label=f"{EMBREE_RATIO_TARGET:g}x Embree")
                    ax.legend(fontsize=7)
                ax.set_xlabel("Mrays/s (closest hit)")
                ax.set_title(f"{m['name']}: {kind} rays", fontsize=9)
                ax.grid(True, axis="x", alpha=0.3)
        written.append(save_figure(fig, out_dir / "bench_bvh_trace.png"))

    leaf = report.get("leaf_size")
    if leaf:
        fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
        sizes = [r["max_leaf_size"] for r in leaf["rows"]]
        axes[0].plot(sizes, [r["incoherent"]["mrays_per_s"] for r in leaf["rows"]], "o-")
        axes[0].set_ylabel("incoherent Mrays/s")
        axes[1].plot(sizes, [r["device_bytes"]["per_triangle"] for r in leaf["rows"]], "o-")
        axes[1].axhline(BYTES_PER_TRIANGLE_TARGET, color="red", ls="--", lw=1)
        axes[1].set_ylabel("device bytes per triangle")
        axes[2].plot(sizes, [r["build_s"] for r in leaf["rows"]], "o-")
        axes[2].set_ylabel("SAH build seconds")
        for ax in axes:
            ax.set_xscale("log", base=2)
            ax.set_xticks(sizes)
            ax.set_xticklabels([str(s) for s in sizes])
            ax.set_xlabel("max_leaf_size")
            ax.grid(True, alpha=0.3)
        fig.suptitle(f"SAH leaf size on {leaf['mesh']}")
        written.append(save_figure(fig, out_dir / "bench_bvh_leaf_size.png"))
    return written

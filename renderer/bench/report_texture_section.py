"""The benchmark page's section of `bench texture-filter` (renderer/bench/texture_filter.py): its
tables rendered from the JSON report, and what filtering costs and buys, in words computed from
the same figures."""
from __future__ import annotations

from renderer.bench.report_markdown import Section, num, table, times, verdict


def _at(points: list[dict], spp: int) -> dict | None:
    return next((p for p in points if p["spp"] == spp), None)


def texture_filter_section(report: dict) -> Section:
    section = Section()
    config = report.get("config", {})
    horizon = report.get("horizon", {})
    curves = horizon.get("curves") or {}
    if curves:
        size = config.get("horizon_size", ["?", "?"])
        rows = [[f, p["spp"], p["seconds"], p["rmse"]] for f, points in curves.items() for p in points]
        section.blocks.append(f"**Checker horizon** ({size[0]}x{size[1]}, path), RMSE against "
                              f"{num(horizon.get('reference_spp'))} spp unfiltered:\n\n"
                              + table(["filter", "spp", "seconds", "RMSE"], rows))
        first = {f: _at(points, min(p["spp"] for p in points)) for f, points in curves.items()}
        none = first.get("none")
        parts = [f"{f} {num(p['rmse'])} ({times(p['rmse'] / none['rmse'])} of unfiltered's error in "
                 f"{times(p['seconds'] / none['seconds'])} its time)" for f, p in first.items()
                 if p is not None and none is not None and f != "none" and none["rmse"] > 0 and none["seconds"] > 0]
        if none is not None and parts:
            section.findings.append(f"At {none['spp']} spp on a checkerboard to the horizon the unfiltered error is "
                                    f"{num(none['rmse'])}; " + "; ".join(parts) + ".")
    for speed in report.get("speeds") or []:
        if "median" not in speed:
            continue
        rows = [[f, speed["median"][f], speed["relative"][f], speed["first_frame_s"][f]] for f in speed["median"]]
        section.blocks.append(f"**Speed, {speed['scene']}** (mis, medians of {num(config.get('rounds'))} interleaved "
                              "rounds):\n\n" + table(["filter", "M samples/s", "vs none", "first frame s"], rows))
        section.findings.append(f"On {speed['scene']} filtering runs at "
                                + ", ".join(f"{times(speed['relative'][f])} ({f})" for f in speed["relative"]
                                            if f != "none") + " of unfiltered's speed.")
    target = report.get("denoise_target") or {}
    if "filters" in target:
        low, high = config.get("target_spp", [8, 128])
        rows = [[f, row[f"denoised_{low}"], row.get(f"denoised_quick_{low}"), row[f"raw_{low}"], row[f"raw_{high}"],
                 verdict(row["passed"])] for f, row in target["filters"].items()]
        size = target.get("size", ["?", "?"])
        section.blocks.append(f"**Denoising target, textured** ({size[0]}x{size[1]}; relMSE less the noise of a "
                              f"{num(target['reference']['spp'])}-spp reference):\n\n"
                              + table(["filter", f"denoised {low} spp", "AOVs not prefiltered", f"raw {low} spp",
                                       f"raw {high} spp", "target"], rows))
        section.findings.append("Denoised at 8 spp against raw at 128 on textured: "
                                + "; ".join(f"{f} {verdict(row['passed'])}" for f, row in target["filters"].items())
                                + ".")
    for key in ("horizon", "denoise_target"):
        skipped = (report.get(key) or {}).get("skipped") if isinstance(report.get(key), dict) else None
        if skipped:
            section.blocks.append(f"{key}: skipped ({skipped}).")
    return section

"""The benchmark page's section of `bench scenes`: the research scenes in pbrt-v4 form beside
Tungsten's references (means, load time, memory, speed) and what the reader left out of each."""
from __future__ import annotations

from renderer.bench.report_markdown import Section, table


def _ratios(row: dict) -> str:
    return " ".join("-" if v is None else f"{v:.3f}" for v in row.get("mean_ratio_rgb") or [])


def _mitsuba_notes(row: dict) -> str:
    if row.get("mitsuba_note"):
        return row["mitsuba_note"]
    notes = row.get("mitsuba_notes") or []
    left_out = [n for n in notes if "left out" in n]  # what changes the scene, before what changes a lobe
    return "; ".join((left_out + [n for n in notes if n not in left_out])[:2]) + (" ..." if len(notes) > 2 else "")


def scenes_section(report: dict) -> Section:
    rows = report.get("results", [])
    rendered = [r for r in rows if "spp" in r]
    section = Section()
    section.findings.append(
        f"{len(rendered)} of {len(rows)} scenes found render at a long side of {report.get('long_side')} pixels "
        f"for {report.get('seconds')} s each; {report.get('passed')} of {report.get('judged')} of the scenes "
        f"whose materials Tungsten and pbrt-v4 define alike ({', '.join(report.get('matched') or [])}) have every "
        f"channel's mean within {100 * (report.get('target') or 0):.0f}% of Tungsten's.")
    section.blocks.append(table(
        ["scene", "size", "spp", "verdict", "mean ratio (R G B)", "load s", "Msamples/s", "triangles", "bytes/triangle",
         "warnings"],
        [[r["scene"], r.get("size", ""), r.get("spp"), r.get("verdict") or "", _ratios(r), r.get("load_s"),
          None if "samples_per_s" not in r else r["samples_per_s"] / 1e6, r.get("triangles"),
          r.get("bytes_per_triangle"), r.get("warnings")] for r in rows]))
    if report.get("mitsuba"):
        converted = [r for r in rows if "mitsuba_spp" in r]
        section.findings.append(
            f"{len(converted)} of {len(rows)} scenes convert to Mitsuba 3 as Lantern reads them; rendered by it for "
            "the same time, their means say whether a difference from Tungsten's lies in the file as read "
            "(Mitsuba / Lantern near 1) or in Lantern (Mitsuba / Tungsten near 1), where the conversion left "
            "nothing out (its notes: a texture left out makes the two scenes differ).")
        section.blocks.append(table(
            ["scene", "Mitsuba / Tungsten (R G B)", "Mitsuba / Lantern (R G B)", "Mitsuba spp", "Mitsuba Msamples/s",
             "Mitsuba load s", "not converted because, or the conversion's notes"],
            [[r["scene"], " ".join(f"{v:.3f}" for v in r.get("mitsuba_mean_ratio_rgb") or []),
              " ".join(f"{v:.3f}" for v in r.get("mitsuba_to_lantern_rgb") or []), r.get("mitsuba_spp"),
              None if "mitsuba_samples_per_s" not in r else r["mitsuba_samples_per_s"] / 1e6, r.get("mitsuba_load_s"),
              _mitsuba_notes(r).replace("<", "&lt;").replace(">", "&gt;")] for r in rows]))
    left_out = [(r["scene"], w) for r in rows for w in (r.get("left_out") or [])] + \
               [(r["scene"], r["note"]) for r in rows if r.get("note")]
    if left_out:
        section.blocks.append(table(["scene", "left out or failed"],
                                    [[s, w.replace("<", "&lt;").replace(">", "&gt;")] for s, w in left_out]))
    return section

"""The benchmark page's section of `bench mitsuba-tests`: how many of Mitsuba 3's render tests pass,
and for each one that does not, why (what the reader left out, or "rendered, differs")."""
from __future__ import annotations

from renderer.bench.report_markdown import Section, table


def _reason(row: dict) -> str:
    """Why a scene did not pass: its load error, the reader's warnings, or a rendered difference
    (tags escaped: the page is Markdown)."""
    if row.get("verdict") == "PASS":
        return ""
    text = row.get("note") or "; ".join(row.get("left_out") or []) or "rendered with every plugin; the image differs"
    return text.replace("<", "&lt;").replace(">", "&gt;")


def mitsuba_tests_section(report: dict) -> Section:
    rows = report.get("results", [])
    passed = sum(r.get("verdict") == "PASS" for r in rows)
    section = Section()
    section.findings.append(
        f"{passed} of {len(rows)} of Mitsuba 3's render tests pass by Mitsuba's own rule (per pixel and channel, "
        f"both images in XYZ, z against the reference's variance at {report.get('rule', {}).get('significance')} "
        f"with Sidak's correction; at least {100 * report.get('rule', {}).get('pass_fraction', 0):.2f} % of the "
        f"channels pass), at the reference's size with Mitsuba's budget of {report.get('sample_budget'):,} samples "
        f"an image.")
    failing = [r for r in rows if r.get("verdict") != "PASS"]
    if failing:
        section.blocks.append(table(["scene not passing", "verdict", "failing %", "mean ratio (R G B)", "why"],
                                    [[r["scene"], r.get("verdict") or "", r.get("failing_percent"),
                                      r.get("mean_ratio_rgb") or "", _reason(r)] for r in failing]))
    section.blocks.append(table(["scene", "size", "spp", "verdict", "failing %", "mean ratio (R G B)", "render s"],
                                [[r["scene"], r.get("size", ""), r.get("spp"), r.get("verdict") or "",
                                  r.get("failing_percent"), r.get("mean_ratio_rgb") or "", r.get("render_s")]
                                 for r in rows]))
    missing = report.get("without_reference") or []
    if missing:
        section.blocks.append(f"Scenes without an RGB reference (not judged): {len(missing)}.")
    return section

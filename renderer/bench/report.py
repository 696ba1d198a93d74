"""`python app.py bench report`: every benchmark's latest figures and plots on one page.

Reads the JSON reports the benchmarks wrote (`--out-dir`, reports/ by default: every *.json there
whose "benchmark" field names one; the latest by its "date" wins) and writes docs/benchmarks.md:
per benchmark the machine, date and command that produced its report, one or two sentences on
what its knobs cost (computed from the figures), its main tables rendered from the JSON, and its
plots, which are copied into docs/benchmarks/ (only those the page shows; others there are
removed). A benchmark without a report keeps its section of the page as it stands (reports are
machine-local, so a later machine that reruns one benchmark must not wipe the others' figures),
or, never reported, gets the command that produces one. A benchmark the page has no section for
(a new one) shows its header, its plots and the records of its report as plain tables. The page
depends only on the reports and the page before: the same inputs give the same bytes.
"""
from __future__ import annotations

import ast
import importlib.util
import json
import re
import sys
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Callable

from renderer.output.atomic_write import write_bytes_atomic, write_text_atomic
from renderer.bench import BENCHMARKS
from renderer.bench.common import REPO_ROOT, describe_error
from renderer.bench.report_error_sections import (
    denoise_section,
    integrators_section,
    photons_section,
    sdf_section,
)
from renderer.bench.report_generic import generic_section
from renderer.bench.report_texture_section import texture_filter_section
from renderer.bench.report_mitsuba_section import mitsuba_tests_section
from renderer.bench.report_scenes_section import scenes_section
from renderer.bench.report_markdown import Section, num
from renderer.bench.report_speed_sections import (
    bvh_section,
    features_section,
    interactive_section,
    startup_section,
)

PAGE_NAME = "benchmarks.md"
PLOT_FOLDER = "benchmarks"  # beside the page: docs/benchmarks/
THIS = "report"  # this command's own name in BENCHMARKS: not a benchmark with a report

SECTIONS: dict[str, Callable[[dict], Section]] = {
    "sdf": sdf_section, "startup": startup_section, "bvh": bvh_section, "integrators": integrators_section,
    "features": features_section, "photons": photons_section, "interactive": interactive_section,
    "denoise": denoise_section, "mitsuba-tests": mitsuba_tests_section, "scenes": scenes_section,
    "texture-filter": texture_filter_section,
}


@dataclass(frozen=True)
class Report:
    """One benchmark's JSON report and the folder its plots are in."""

    path: Path
    data: dict

    @property
    def name(self) -> str:
        """The benchmark, and the variant its header names for a run with options of its own
        (`interactive --packets 8`: interactive-packets8), kept beside the plain run's report."""
        variant = self.data.get("variant")
        return self.data["benchmark"] + (f"-{variant}" if isinstance(variant, str) and variant else "")

    @property
    def benchmark(self) -> str:
        return self.data["benchmark"]

    def plot_names(self) -> list[str]:
        """The PNGs the report lists ("plots", or "plot" for a single one), in its order."""
        plots = self.data.get("plots", self.data.get("plot"))
        names = [plots] if isinstance(plots, str) else list(plots or [])
        return [n for n in names if isinstance(n, str) and n.lower().endswith(".png")]


def _when(data: dict) -> datetime:
    try:
        return datetime.fromisoformat(str(data.get("date")))
    except ValueError:
        return datetime.min


def latest_reports(reports_dir: Path, warn: Callable[[str], None]) -> dict[str, Report]:
    """The latest report of each benchmark in `reports_dir` (by the date in its header; the file
    name breaks ties). JSON files that are not benchmark reports are passed over; unreadable
    ones are named in a warning and skipped."""
    latest: dict[str, Report] = {}
    for path in sorted(Path(reports_dir).glob("*.json")):
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, ValueError) as error:
            warn(f"{path}: not a readable JSON report ({describe_error(error)}); skipped")
            continue
        if not isinstance(data, dict) or not isinstance(data.get("benchmark"), str):
            continue
        report = Report(path, data)
        held = latest.get(report.name)
        if held is None or (_when(data), path.name) > (_when(held.data), held.path.name):
            latest[report.name] = report
    return latest


def purpose(name: str) -> str:
    """The first paragraph of the benchmark module's docstring, without its command prefix (read
    from the source: benchmark modules start Taichi when imported)."""
    try:
        spec = importlib.util.find_spec(BENCHMARKS.get(name, f"renderer.bench.{name}"))
    except (ImportError, ValueError):
        spec = None
    if spec is None or not spec.origin or not spec.origin.endswith(".py"):
        return ""
    doc = ast.get_docstring(ast.parse(Path(spec.origin).read_text(encoding="utf-8"))) or ""
    first = " ".join(doc.split("\n\n")[0].split())
    first = re.sub(r"^`python app\.py bench [\w-]+`:\s*", "", first)
    return first[:1].upper() + first[1:]


def how_to_produce(name: str) -> str:
    return (f"No report yet: run `python app.py bench {name}` (writes its JSON and plots to reports/), then "
            f"`python app.py bench {THIS}`.")


def provenance(data: dict) -> str:
    """Where the figures come from: when, by which command, on which machine, under what load."""
    machine = data.get("machine") or {}
    when = _when(data)
    date = when.strftime("%Y-%m-%d %H:%M %Z").strip() if when != datetime.min else "an unknown date"
    run = "a `--quick` run" if data.get("quick") else "a full run"
    total = data.get("total_seconds")
    took = f", {num(total / 60, 2)} min" if isinstance(total, (int, float)) else ""
    software = ", ".join(f"{label} {machine[key]}" for key, label in (("python", "Python"), ("taichi", "Taichi"))
                         if machine.get(key))
    text = (f"Measured {date} by `{data.get('command', '?')}` ({run}{took}) on "
            f"{machine.get('processor', 'an unknown CPU')} with {machine.get('cpus', '?')} CPUs "
            f"({machine.get('platform', '?')}; {software})")
    load = data.get("load_average") or {}
    if load.get("before") or load.get("after"):
        def show(values):
            return " / ".join(num(v) for v in values) if values else "?"
        text += f"; load average (1 / 5 / 15 min) {show(load.get('before'))} before, {show(load.get('after'))} after"
    return text + "."


def _section(report: Report) -> tuple[Section, str | None]:
    """The benchmark's own section; the generic one (and why) if the report does not have the
    layout the section reads, so one changed benchmark cannot take the page down."""
    build = SECTIONS.get(report.benchmark)
    if build is None:
        return generic_section(report.data), None
    try:
        return build(report.data), None
    except (KeyError, IndexError, TypeError, ValueError, ZeroDivisionError, StopIteration) as error:
        return generic_section(report.data), describe_error(error)


def page_names(found: dict[str, Report]) -> list[str]:
    """The registry's benchmarks in its order, then any other benchmark that left a report."""
    names = [n for n in BENCHMARKS if n != THIS]
    return names + sorted(n for n in found if n not in names)


@dataclass(frozen=True)
class Page:
    text: str  # the Markdown
    plots: dict[str, Path]  # the PNGs it shows: file name -> the report's PNG
    reported: tuple[str, ...]  # the benchmarks it shows a report of
    kept_plots: tuple[str, ...] = ()  # PNGs of sections kept from the page before (already in place)


_SECTION_HEADING = re.compile(r"^## (\S+)$")
_INDEX_ROW = re.compile(r"^\| \[(\S+)\]\(#\S+\) \| .* \| (.+) \|$")
_PLOT = re.compile(r"!\[[^\]]*\]\(" + re.escape(PLOT_FOLDER) + r"/([^)]+)\)")


def previous_sections(text: str | None) -> dict[str, tuple[str, list[str]]]:
    """{benchmark: (its 'latest report' cell, the lines of its section)} of a page written before,
    for the benchmarks it showed a report of."""
    if not text:
        return {}
    dates = {m.group(1): m.group(2) for m in map(_INDEX_ROW.match, text.splitlines()) if m}
    sections, name = {}, None
    for line in text.splitlines():
        heading = _SECTION_HEADING.match(line)
        if heading:
            name = heading.group(1)
            sections[name] = []
        elif name is not None:
            sections[name].append(line)
    return {n: (dates.get(n, "earlier"), lines) for n, lines in sections.items()
            if dates.get(n, "none yet") != "none yet" and not any(how_to_produce(n) in line for line in lines)}


def build_page(reports_dir: Path, warn: Callable[[str], None] = print, previous: str | None = None) -> Page:
    """The page from the latest reports in `reports_dir`; `previous`, the page as it stood, gives
    the sections of benchmarks with no report here."""
    found = latest_reports(reports_dir, warn)
    kept = previous_sections(previous)
    plots: dict[str, Path] = {}
    kept_plots: list[str] = []
    index = ["| benchmark | measures | latest report |", "| --- | --- | --- |"]
    body = []
    for name in page_names(found):
        report = found.get(name)
        what = purpose(report.benchmark if report is not None else name)
        if report is None and name in kept:
            when, lines = kept[name]
            index.append(f"| [{name}](#{name}) | {what.replace('|', '/')} | {when} |")
            while lines and lines[-1] == "":
                lines = lines[:-1]
            body += ["", f"## {name}", *lines]
            kept_plots += [m.group(1) for line in lines for m in _PLOT.finditer(line)]
            continue
        when = (f"{_when(report.data):%Y-%m-%d}" + (" (--quick)" if report.data.get("quick") else "")
                if report else "none yet")
        index.append(f"| [{name}](#{name}) | {what.replace('|', '/')} | {when} |")
        body += ["", f"## {name}", ""]
        if what:
            body += [what, ""]
        if report is None:
            body.append(how_to_produce(name))
            continue
        body += [provenance(report.data), ""]
        section, fallback = _section(report)
        if fallback:
            body += [f"(The page's section for `{name}` could not read this report ({fallback}); its records "
                     f"are shown as they are.)", ""]
        if section.findings:
            body += ["**What it costs.** " + " ".join(section.findings), ""]
        for block in section.blocks:
            body += [block, ""]
        for plot in report.plot_names():
            source = report.path.parent / plot
            if source.is_file():
                plots[plot] = source
                body += [f"![{plot}]({PLOT_FOLDER}/{plot})", ""]
            else:
                body += [f"(Plot `{plot}` is listed in the report but missing beside it.)", ""]
        while body and body[-1] == "":
            body.pop()
    head = ["# Benchmarks", "",
            "What Lantern's accuracy knobs cost in time, as last measured: every benchmark's latest report with the "
            "machine, date and command that produced it, its main tables and its plots (error against time for "
            "every knob that trades one for the other). `python app.py bench NAME` runs a benchmark and writes its "
            f"JSON and plots to reports/; `python app.py bench {THIS}` rebuilds this page from the latest report of "
            "each (the page is generated: edit the benchmarks or renderer/bench/report.py, not this file).", ""]
    return Page("\n".join(head + index + body) + "\n", plots, tuple(sorted(found)), tuple(kept_plots))


def write_page(page: Page, docs_dir: Path) -> Path:
    """The page and its plots (copied only where the bytes differ); PNGs of earlier pages that this
    one does not show are removed."""
    folder = Path(docs_dir) / PLOT_FOLDER
    folder.mkdir(parents=True, exist_ok=True)
    for name, source in sorted(page.plots.items()):
        target = folder / name
        data = source.read_bytes()
        if not target.is_file() or target.read_bytes() != data:
            write_bytes_atomic(target, data)
    for stale in sorted(folder.glob("*.png")):
        if stale.name not in page.plots and stale.name not in page.kept_plots:
            stale.unlink()
    path = Path(docs_dir) / PAGE_NAME
    write_text_atomic(path, page.text)
    return path


def run(quick: bool = False, out_dir: Path = Path("reports"), docs_dir: Path | None = None) -> int:
    """Write docs/benchmarks.md (or `docs_dir`/benchmarks.md) from the reports in `out_dir`;
    `quick` changes nothing (the page only reads what the benchmarks measured)."""
    out_dir = Path(out_dir)
    if not out_dir.is_dir():
        print(f"{out_dir}: no such folder of benchmark reports (run `python app.py bench NAME` first)",
              file=sys.stderr)
        return 1
    docs_dir = Path(docs_dir) if docs_dir is not None else REPO_ROOT / "docs"
    before = docs_dir / PAGE_NAME
    page = build_page(out_dir, lambda line: print(line, file=sys.stderr),
                      before.read_text(encoding="utf-8") if before.is_file() else None)
    path = write_page(page, docs_dir)
    print(f"wrote {path}: reports of {', '.join(page.reported) or 'no benchmark'}; {len(page.plots)} plots in "
          f"{path.parent / PLOT_FOLDER}")
    return 0

"""`bench report` (renderer/bench/report.py): the benchmark page, docs/benchmarks.md, from reports
shaped like the benchmarks' own (tests/bench/report_fixtures.py), written to temporary folders."""
import json
import math
import re
import shutil
from datetime import datetime

import pytest

from renderer.bench import BENCHMARKS
from renderer.bench.report import PAGE_NAME, PLOT_FOLDER, build_page, how_to_produce, run
from renderer.bench.report_markdown import listing, num, pct, table, times, verdict
from tests.bench.report_fixtures import WRITERS, integrators_report


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    """Every benchmark's report and plots in one folder: (folder, {name: report})."""
    folder = tmp_path_factory.mktemp("reports")
    return folder, {name: write(folder) for name, write in WRITERS.items()}


def make_page(reports_dir, docs_dir) -> str:
    assert run(out_dir=reports_dir, docs_dir=docs_dir) == 0
    return (docs_dir / PAGE_NAME).read_text(encoding="utf-8")


def sections(page: str) -> dict:
    """{benchmark name: its section's text}."""
    parts = re.split(r"^## ", page, flags=re.M)[1:]
    return {part.split("\n", 1)[0]: part for part in parts}


def tables(text: str) -> list:
    """The Markdown tables of `text`, each as rows of cells (header first, separator left out)."""
    found, current = [], []
    for line in text.splitlines() + [""]:
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
            if not all(re.fullmatch(r"-+:?", c) for c in cells):
                current.append(cells)
        elif current:
            found.append(current)
            current = []
    return found


def row(text: str, *first_cells: str) -> dict:
    """The table row whose first cells are `first_cells`, as {column header: cell}."""
    for t in tables(text):
        for cells in t[1:]:
            if cells[:len(first_cells)] == list(first_cells):
                return dict(zip(t[0], cells))
    raise AssertionError(f"no row {first_cells}")


def linked_plots(page: str) -> list:
    return re.findall(r"!\[[^\]]*\]\(([^)]+)\)", page)


def test_every_benchmark_shows_where_its_figures_come_from_what_they_cost_and_its_plots(reports, tmp_path):
    folder, data = reports
    page = make_page(folder, tmp_path / "docs")
    by_name = sections(page)
    registered = [n for n in BENCHMARKS if n != "report"]  # the registry's order, less this command
    assert list(by_name) == registered + sorted(set(data) - set(registered))
    for name, report in data.items():
        text = by_name[name]
        machine = report["machine"]
        assert f"`{report['command']}`" in text
        assert machine["processor"] in text and f"{machine['cpus']} CPUs" in text
        assert f"{datetime.fromisoformat(report['date']):%Y-%m-%d %H:%M} UTC" in text
        assert ("a `--quick` run" if report["quick"] else "a full run") in text
        assert "could not read this report" not in text  # each section reads its benchmark's layout
        assert "**What it costs.** " in text
        plots = report.get("plots") or ([report["plot"]] if "plot" in report else [])  # startup draws none
        assert [f"{PLOT_FOLDER}/{p}" for p in plots] == linked_plots(text)
        assert f"| [{name}](#{name}) |" in page


def test_tables_are_rendered_from_the_json(reports, tmp_path):
    folder, data = reports
    text = sections(make_page(folder, tmp_path / "docs"))
    box = data["integrators"]["scenes"][0]
    curve = next(c for c in box["curves"] if (c["integrator"], c["sampler"]) == ("nee", "sobol"))
    cells = row(text["integrators"], "nee/sobol")
    assert cells["relMSE"] == num(curve["at_budget"]["rel_mse"])
    assert cells["spp at T"] == num(round(curve["at_budget"]["spp"]))
    whole = data["integrators"]["whole_process"]
    cells = row(text["integrators"], "Lantern render mis")
    assert cells["median s"] == num(whole["lantern"]["median_s"]) and cells["RMSE"] == num(whole["lantern"]["rmse"])
    assert cells["time vs Mitsuba"] == f"{whole['ratio']:.2f}x"
    assert f"Lantern's render command takes {num(whole['lantern']['median_s'])} s" in text["integrators"]
    assert (f"the render alone takes {num(whole['lantern']['render_median_s'])} s against "
            f"{num(whole['mitsuba']['render_median_s'])} s ({times(whole['render_ratio'])})") in text["integrators"]
    assert row(text["integrators"], "Mitsuba (process)")["start-up and the rest s"] == num(0.5)
    mesh = data["integrators"]["mesh_heavy"]
    cells = row(text["integrators"], "Lantern mis/sobol")
    assert cells["seconds to target"] == num(mesh["rows"]["Lantern mis/sobol"]["seconds_to_target"])
    assert f"at {times(mesh['best_ratio'])} the speed of Mitsuba's best" in text["integrators"]
    alpha = data["sdf"]["scenes"][0]
    cells = row(text["sdf"], "alpha")
    assert cells["fewer steps"] == pct(alpha["target"]["step_reduction"])
    assert cells["target"] == ("PASS" if alpha["target"]["passed"] else "FAIL")
    large = data["bvh"]["meshes"][1]
    sah = next(b for b in large["builds"] if b["strategy"] == "sah")
    assert row(text["bvh"], "large", "1,000,000", "sah")["build s"] == num(sah["seconds"])
    wide = next(w for w in large["wide_vs_binary"] if (w["strategy"], w["triangle_test"]) == ("sah", "moller"))
    assert row(text["bvh"], "large", f"sah/{wide['traversal']}/moller")["incoherent"] == \
        f"{wide['incoherent']['speedup']:.2f}x"
    packed = next(w for w in large["packets_vs_scalar"]
                  if (w["strategy"], w["traversal"], w["triangle_test"]) == ("sah", "wide4", "watertight"))
    assert f"packet leaves run at {packed['incoherent']['speedup']:.2f}x the scalar leaves'" in text["bvh"]
    assert "Packet leaves (`+packets`" in text["bvh"]
    warm = data["startup"]["measurements"][1]["warm"]
    cells = row(text["startup"], "viewer, kernels for compile")
    assert cells["warm: to first frame"] == num(warm["start_to_first_frame"])
    sppm = data["photons"]["scenes"][0]["curves"]["sppm"]
    assert row(text["photons"], "sppm")["caustic −floor"] == num(sppm["at_budget_floor_corrected"]["rel_mse_caustic"])
    mis = next(r for r in data["interactive"]["results"] if r["integrator"] == "mis")
    assert row(text["interactive"], "box", "mis")["p95 ms"] == num(mis["latency_p95_ms"])
    first = row(text["interactive"], "box", "mis")["first round vs whole-sample frames"]
    assert first == times(mis["still"]["first_round"]["rate_ratio"], 3)
    assert row(text["interactive"], "box", "path")["first round vs whole-sample frames"] == "-"
    assert "after a view's first round (87.8 % during it, its slices interleaved)" in text["interactive"]
    beta = next(s for s in data["features"]["scenes"] if s["scene"] == "beta")
    ratio = beta["builds"]["everything"]["vs_own"]
    expected = f"{ratio['median']:.3f} [{ratio['lo']:.3f}, {ratio['hi']:.3f}]"
    assert row(text["features"], "beta")["t(all) / t(own)"] == expected

    room = data["denoise"]["scenes"][1]
    assert row(text["denoise"], "room")["denoised at 8 spp"] == num(room["target_denoise"]["denoised_8"])
    viewer = next(t for t in tables(text["denoise"]) if "denoised at 8, with" in t[0])
    cells = dict(zip(viewer[0], next(c for c in viewer[1:] if c[0] == "room")))
    assert cells["denoised at 8, none"] == num(room["viewer_size"]["denoised_8_without_features"])
    assert cells["denoised at 8, with"] == num(room["viewer_size"]["denoised_8_with_features"])
    assert cells["feature samples"] == "4 each" and cells["target"] == ("PASS" if room["viewer_size"]["passed"] else "FAIL")
    assert "at the viewer's 960x540" in text["denoise"]

    # a figure changed in the JSON changes the page
    changed = tmp_path / "changed"
    shutil.copytree(folder, changed)
    report = json.loads((changed / "bench_photons.json").read_text())
    report["scenes"][0]["curves"]["sppm"]["at_budget_floor_corrected"]["rel_mse_caustic"] = 0.0123
    (changed / "bench_photons.json").write_text(json.dumps(report))
    assert row(sections(make_page(changed, tmp_path / "docs2"))["photons"], "sppm")["caustic −floor"] == "0.0123"


def test_the_cost_sentences_follow_the_figures(tmp_path):
    integrators_report(tmp_path, {"box": {"path/independent": 0.4, "mis/sobol": 0.02, "nee/sobol": 0.05},
                                  "room": {"path/independent": 0.4, "mis/sobol": 0.05, "nee/sobol": 0.01},
                                  "hall": {"path/independent": 0.3, "mis/sobol": 0.03, "nee/sobol": 0.04}})
    text = sections(make_page(tmp_path, tmp_path / "docs"))["integrators"]
    findings = text.split("**What it costs.** ", 1)[1].split("\n", 1)[0]
    # errors fall as 1/seconds alike, so the ratios at equal time are those of the errors at 1 s
    assert "the lowest relMSE is mis/sobol's on box and hall; nee/sobol's on room" in findings
    assert "plain path tracing (path/independent) ends at 10.0x–40.0x that" in findings


def test_a_benchmark_without_a_report_says_how_to_produce_one(reports, tmp_path):
    folder, data = reports
    only = tmp_path / "reports"
    only.mkdir()
    for name in [*data["photons"]["plots"], "bench_photons.json"]:
        shutil.copy(folder / name, only / name)
    page = make_page(only, tmp_path / "docs")
    by_name = sections(page)
    for name in BENCHMARKS:
        if name not in ("report", "photons"):
            assert how_to_produce(name) in by_name[name]
            assert f"`python app.py bench {name}`" in how_to_produce(name)
            index_row = page.split(f"| [{name}](#{name}) |", 1)[1].split("\n", 1)[0]
            assert index_row.endswith("| none yet |")
    assert "No report yet" not in by_name["photons"]
    assert sorted(p.name for p in (tmp_path / "docs" / PLOT_FOLDER).iterdir()) == sorted(data["photons"]["plots"])


def test_plot_links_resolve_and_only_the_plots_shown_are_copied(reports, tmp_path):
    folder, _ = reports
    source = tmp_path / "reports"
    shutil.copytree(folder, source)
    (source / "bench_sdf_not_listed.png").write_bytes((source / "bench_features.png").read_bytes())
    docs = tmp_path / "docs"
    (docs / PLOT_FOLDER).mkdir(parents=True)
    (docs / PLOT_FOLDER / "bench_gone.png").write_bytes(b"an earlier page's plot")
    page = make_page(source, docs)
    links = linked_plots(page)
    assert len(links) == len(set(links)) > 10
    for link in links:
        target = docs / link
        assert target.is_file() and target.read_bytes() == (source / target.name).read_bytes()
    assert sorted(p.name for p in (docs / PLOT_FOLDER).iterdir()) == sorted(link.split("/", 1)[1] for link in links)

    # a plot the report lists but that is not there is named, not linked
    (source / "bench_bvh_trace.png").unlink()
    page = make_page(source, docs)
    assert "bench_bvh_trace.png" not in linked_plots(page)
    assert "(Plot `bench_bvh_trace.png` is listed in the report but missing beside it.)" in page
    assert not (docs / PLOT_FOLDER / "bench_bvh_trace.png").exists()


def test_the_page_is_deterministic(reports, tmp_path):
    folder, _ = reports
    first = make_page(folder, tmp_path / "a")
    assert make_page(folder, tmp_path / "a") == first  # again over its own output
    shuffled = tmp_path / "shuffled"
    shuffled.mkdir()
    for path in sorted(folder.iterdir(), reverse=True):  # other creation order, other folder
        shutil.copy(path, shuffled / path.name)
    assert make_page(shuffled, tmp_path / "b") == first
    assert {p.name: p.read_bytes() for p in (tmp_path / "a" / PLOT_FOLDER).iterdir()} == \
        {p.name: p.read_bytes() for p in (tmp_path / "b" / PLOT_FOLDER).iterdir()}


def test_the_latest_report_of_a_benchmark_wins(reports, tmp_path):
    folder, data = reports
    source = tmp_path / "reports"
    shutil.copytree(folder, source)
    older = json.loads((source / "bench_photons.json").read_text())
    older["date"] = "2020-01-01T00:00:00+00:00"
    older["command"] = "python app.py bench photons --quick"
    (source / "zz_photons_older.json").write_text(json.dumps(older))
    text = sections(make_page(source, tmp_path / "docs"))["photons"]
    assert f"`{data['photons']['command']}`" in text and older["command"] not in text
    older["date"] = "2999-01-01T00:00:00+00:00"
    (source / "zz_photons_older.json").write_text(json.dumps(older))
    assert f"`{older['command']}`" in sections(make_page(source, tmp_path / "docs"))["photons"]


def test_unreadable_json_is_named_in_one_line_and_passed_over(reports, tmp_path, capsys):
    folder, _ = reports
    source = tmp_path / "reports"
    shutil.copytree(folder, source)
    (source / "broken.json").write_text('{"benchmark": "sdf", ')
    (source / "other.json").write_text('{"not": "a benchmark report"}')
    page = make_page(source, tmp_path / "docs")
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{source / 'broken.json'}: not a readable JSON report (")
    assert lines[0].endswith("; skipped")
    assert "No report yet" not in sections(page)["sdf"]
    assert run(out_dir=tmp_path / "nowhere", docs_dir=tmp_path / "docs") == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"{tmp_path / 'nowhere'}: no such folder of benchmark reports "
                   f"(run `python app.py bench NAME` first)"]


def test_a_report_the_page_has_no_section_for_is_shown_as_it_is(reports, tmp_path):
    folder, data = reports
    source = tmp_path / "reports"
    source.mkdir()
    shutil.copy(folder / "bench_features.png", source / "bench_novel.png")
    new = {**{k: data["photons"][k] for k in ("quick", "date", "command", "machine", "load_average")},
           "benchmark": "novel", "config": {"size": [8, 8]},
           "results": [{"scene": "box", "spp": 4, "rel_mse": 0.25, "curve": [1, 2]},
                       {"scene": "room", "spp": 8, "rel_mse": 0.125, "curve": [3]}],
           "summary": {"passed": True, "seconds": 1.5}, "plots": ["bench_novel.png"]}
    (source / "novel.json").write_text(json.dumps(new))
    # a known benchmark whose report lacks what its section reads
    drifted = {**data["photons"], "scenes": [{"scene": "goblet", "curves": {}}]}
    (source / "bench_photons.json").write_text(json.dumps(drifted))
    by_name = sections(make_page(source, tmp_path / "docs"))
    assert list(by_name)[-1] == "novel"  # after the registry's benchmarks
    text = by_name["novel"]
    assert f"`{new['command']}`" in text and linked_plots(text) == [f"{PLOT_FOLDER}/bench_novel.png"]
    assert row(text, "room") == {"scene": "room", "spp": "8", "rel_mse": "0.125"}  # plain values only
    assert row(text, "passed") == {"": "passed", "value": "yes"}
    assert "could not read this report (KeyError" in by_name["photons"]
    assert row(by_name["photons"], "goblet")["scene"] == "goblet"


def test_markdown_pieces():
    assert [num(v) for v in (None, True, 12345, 0.0, 0.125, 12345.6, 1234567.0, 0.000123, -2.5e-7, "inf", "x")] == \
        ["–", "yes", "12,345", "0", "0.125", "12,300", "1.23e6", "1.23e-4", "-2.50e-7", "∞", "x"]
    assert num(math.inf) == "∞" and num(math.nan) == "–"
    assert pct(-0.0, signed=True) == "+0.0 %" and pct(0.25) == "25.0 %" and pct(None) == "–"
    assert listing(["a"]) == "a" and listing(["a", "b", "c"]) == "a, b and c"
    assert table(["name", "x", "ratio"], [["a|b", 1.5, "2.00x"], ["c", None, "–"]]).splitlines() == [
        "| name | x | ratio |", "| --- | ---: | ---: |", "| a\\|b | 1.5 | 2.00x |", "| c | – | – |"]


def test_build_page_needs_no_plots_on_disk_to_name_them(tmp_path):
    (tmp_path / "bench_x.json").write_text(json.dumps({"benchmark": "x", "date": "2026-01-02T03:04:05+00:00",
                                                       "plots": ["a.png", "b.svg"], "rows": [{"v": 1}]}))
    page = build_page(tmp_path, warn=lambda line: pytest.fail(line))
    text = page.text
    assert page.plots == {} and page.reported == ("x",)
    assert "(Plot `a.png` is listed in the report but missing beside it.)" in text
    assert "b.svg" not in text  # only PNGs are plots on the page
    assert "Measured 2026-01-02 03:04 UTC by `?`" in sections(text)["x"]


def test_the_mitsuba_comparison_says_how_its_best_samplers_were_measured(tmp_path):
    """With Mitsuba measured: the caption names the rows measured over seeds (levels, seeds) and the
    findings give best sampler against best, as the JSON has them."""
    from renderer.bench.report_error_sections import integrators_section

    report = integrators_report(tmp_path)
    row = {"samples_per_s": 1.5e6, "rmse_at_target_spp": 0.0383, "extrapolated": False}
    report["mitsuba"] = {
        "available": True, "version": "3.9.1", "variant": "llvm_ad_rgb", "threads": 2, "size": [128, 128],
        "max_depth": 8, "reference": {"spp": 2048}, "target_spp": 64, "target_rmse": 0.0383, "target_renders": 8,
        "passed": False, "seeded": {"levels": [8, 16, 32, 64], "renders": 16,
                                    "rows": ["mis/sobol", "nee/sobol", "mitsuba/multijitter"]},
        "rows": {"mitsuba": {**row, "spp_to_target": 64.0, "seconds_to_target": 0.5},
                 "mis/independent": {**row, "spp_to_target": 77.0, "seconds_to_target": 0.72},
                 "mis/sobol": {**row, "spp_to_target": 11.66, "seconds_to_target": 0.118},
                 "mitsuba/multijitter": {**row, "spp_to_target": 11.47, "seconds_to_target": 0.096}}}
    section = integrators_section(report)
    text = "\n".join(section.blocks)
    assert ("except mis/sobol, nee/sobol and mitsuba/multijitter: mean errors of 16 seeds at 8, 16, 32 and 64 spp, "
            "rendered in turn, and timed by the 64-spp renders") in text
    best = next(f for f in section.findings if f.startswith("Best sampler against best"))
    assert "0.118 s (11.7 spp) against Mitsuba multijitter's 0.096 s (11.5 spp): 0.81x Mitsuba's speed" in best


def test_a_later_run_of_one_benchmark_keeps_the_others_sections(reports, tmp_path):
    """Reports are machine-local: rebuilding the page from one new report keeps every other
    benchmark's section, its date and its plots as the page had them."""
    folder, data = reports
    docs = tmp_path / "docs"
    full = make_page(folder, docs)
    only = tmp_path / "only_photons"
    only.mkdir()
    for name in [*data["photons"]["plots"], "bench_photons.json"]:
        shutil.copy(folder / name, only / name)
    again = make_page(only, docs)
    before, after = sections(full), sections(again)
    for name in before:
        assert after[name].rstrip() == before[name].rstrip(), name
        row = f"| [{name}](#{name}) |"
        assert full.split(row, 1)[1].split("\n", 1)[0] == again.split(row, 1)[1].split("\n", 1)[0]
    assert sorted(p.name for p in (docs / PLOT_FOLDER).iterdir()) == sorted(l.split("/", 1)[1] for l in linked_plots(full))
    # With no page before, the same single report leaves the others "none yet" (as it did).
    fresh = make_page(only, tmp_path / "fresh_docs")
    assert how_to_produce("sdf") in sections(fresh)["sdf"]


def test_the_texture_filter_section_reads_its_report(reports, tmp_path):
    folder, data = reports
    text = sections(make_page(folder, tmp_path / "docs"))["texture-filter"]
    report = data["texture-filter"]
    first = report["horizon"]["curves"]["anisotropic"][0]
    assert row(text, "anisotropic", "1")["RMSE"] == num(first["rmse"])
    none = report["horizon"]["curves"]["none"][0]
    assert f"{times(first['rmse'] / none['rmse'])} of unfiltered's error" in text
    assert row(text, "trilinear", num(2.4))["vs none"] == num(2.4 / 2.7)
    assert row(text, "none", num(0.015))["target"] == verdict(False)
    assert row(text, "trilinear", num(0.01))["target"] == verdict(True)


def test_a_packets_run_of_the_interactive_benchmark_is_kept_beside_the_plain_one(reports, tmp_path):
    folder, data = reports
    source = tmp_path / "reports"
    shutil.copytree(folder, source)
    packed = json.loads((source / "bench_interactive.json").read_text())
    packed["config"] = {**packed["config"], "packets": 8}
    packed["variant"] = "packets8"  # as interactive.run writes it
    packed["command"] = "python app.py bench interactive --packets 8"
    packed["results"][0]["moving"]["pixel_share_median"] = 0.375
    (source / "bench_interactive_packets8.json").write_text(json.dumps(packed))
    found = sections(make_page(source, tmp_path / "docs"))
    assert f"`{data['interactive']['command']}`" in found["interactive"]
    text = found["interactive-packets8"]
    assert "`python app.py bench interactive --packets 8`" in text and "8 rays a packet" in text
    assert row(text, "box", "path")["moving film (share of the window)"] == "37.5 %"
    assert row(text, "box", "mis")["moving film (share of the window)"] == "-"

"""What each kernel optimisation level costs and gives back, the figures behind
renderer/runtime/optimize_choice.py. For each scene and level (renderer.runtime.arch.OPTIMIZE_FOR), each
measurement a fresh process:

  cold start  on an empty offline cache (a new temporary directory): Renderer built and its first
              pixel slice rendered, i.e. every kernel a render needs compiled (scene upload, film,
              the integrator); the slice's own work is negligible
  rate        on the cache the last cold start filled: the warm start, then samples per second
              over whole samples per pixel, the fastest of --chunks passes of about --seconds
              each (on a shared machine, the least disturbed one)

Levels and scenes are interleaved (scene a compile, a run, b compile, b run, ... then again) so
the drifts of a shared machine spread over all of them; the table gives medians over the repeats
and of the ratios taken within each repeat (neighbours in time).

    nice -n 10 python scripts/optimize_costs.py [SCENE ...] [--size WxH] [--cold-repeats N]
                                                [--rate-repeats N] [--seconds S] [--chunks K]

Writes reports/optimize_costs.json.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

MARKER = "LANTERN-OPTIMIZE-COSTS "
DEFAULT_SCENES = ("showcase", "cornell_box", "bunnies")
CHILD_TIMEOUT = 1800.0


def child_main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--scene", required=True)
    parser.add_argument("--optimize", required=True)
    parser.add_argument("--size", required=True)
    parser.add_argument("--seconds", type=float, required=True)
    parser.add_argument("--chunks", type=int, required=True, help="timed passes (0: the start alone)")
    parser.add_argument("--cache-dir", required=True)
    args = parser.parse_args(argv)
    import taichi as ti

    from renderer.runtime.arch import init_taichi
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any, resolve_scene

    width, height = (int(v) for v in args.size.split("x"))
    arch = init_taichi("cpu", cache_dir=args.cache_dir, optimize=args.optimize)
    scene = load_any(resolve_scene(args.scene))
    camera = CameraFrame.from_spec(scene.camera)
    start, start_cpu = time.perf_counter(), time.process_time()
    renderer = Renderer(scene, (width, height))
    renderer.render_slices(camera, 1)
    ti.sync()
    report = {"scene": scene.name, "geometry": scene.geometry, "integrator": scene.render.integrator,
              "max_depth": scene.render.max_depth, "optimize": args.optimize, "arch": arch,
              "threads": len(os.sched_getaffinity(0)), "start_s": time.perf_counter() - start,
              "start_cpu_s": time.process_time() - start_cpu}
    if args.chunks:
        t0 = time.perf_counter()
        renderer.render(camera, 1)  # one sample per pixel: the size of the timed passes
        ti.sync()
        spp = max(1, round(args.seconds / max(time.perf_counter() - t0, 1e-6)))
        chunks, chunks_cpu = [], []
        for _ in range(args.chunks):
            t0, c0 = time.perf_counter(), time.process_time()
            renderer.render(camera, spp)
            ti.sync()
            chunks.append(time.perf_counter() - t0)
            chunks_cpu.append(time.process_time() - c0)
        samples = spp * width * height
        report.update(spp=spp, chunk_s=chunks, chunk_cpu_s=chunks_cpu, samples_per_s=samples / min(chunks),
                      core_s_per_sample=statistics.median(chunks_cpu) / samples)
    print(MARKER + json.dumps(report), flush=True)
    return 0


def measure(scene: str, optimize: str, args, cache_dir: str, chunks: int) -> dict:
    from renderer.bench.common import child_report, run_module

    options = ["--child", "--scene", scene, "--optimize", optimize, "--size", args.size, "--seconds", str(args.seconds),
               "--chunks", str(chunks), "--cache-dir", cache_dir]
    proc = run_module("scripts.optimize_costs", options, CHILD_TIMEOUT)
    report, problem = child_report(proc.stdout, proc.stderr, proc.returncode, MARKER)
    if report is None:
        raise RuntimeError(f"{scene} at {optimize}: {problem}")
    return report


def summarise(cold: list[dict], rates: list[dict]) -> list[dict]:
    """Per scene: medians of each level's figures, and of the differences and ratios within each
    repeat. CPU time (every thread of the process) rather than wall time decides: on a shared
    machine it counts only the time the process ran, where wall time also counts the waits for a
    core. A compile's CPU time is at least its wall time on an idle machine (Taichi may compile a
    kernel's tasks on a few threads), so the break-even errs long."""
    rows = []
    for scene in dict.fromkeys(r["scene"] for r in rates):
        def of(runs, level):
            return [r for r in runs if r["scene"] == scene and r["optimize"] == level]

        cold_pairs = list(zip(of(cold, "compile"), of(cold, "run")))
        rate_pairs = list(zip(of(rates, "compile"), of(rates, "run")))
        row = {"scene": scene, "geometry": rate_pairs[0][0]["geometry"], "cold_repeats": len(cold_pairs),
               "rate_repeats": len(rate_pairs),
               "warm_start_compile_s": statistics.median(a["start_s"] for a, _ in rate_pairs),
               "warm_start_run_s": statistics.median(b["start_s"] for _, b in rate_pairs),
               "rate_compile": statistics.median(a["samples_per_s"] for a, _ in rate_pairs),
               "rate_run": statistics.median(b["samples_per_s"] for _, b in rate_pairs),
               # CPU core-seconds per sample at the compile level
               "core_s_per_sample": statistics.median(a["core_s_per_sample"] for a, _ in rate_pairs),
               # CPU time at the run level per CPU second at the compile level, for the same samples
               "time_ratio": statistics.median(b["core_s_per_sample"] / a["core_s_per_sample"] for a, b in rate_pairs)}
        if cold_pairs:
            row.update(cold_start_compile_s=statistics.median(a["start_s"] for a, _ in cold_pairs),
                       cold_start_run_s=statistics.median(b["start_s"] for _, b in cold_pairs),
                       cold_cpu_compile_s=statistics.median(a["start_cpu_s"] for a, _ in cold_pairs),
                       cold_cpu_run_s=statistics.median(b["start_cpu_s"] for _, b in cold_pairs),
                       extra_cold_cpu_s=statistics.median(b["start_cpu_s"] - a["start_cpu_s"] for a, b in cold_pairs))
            saved = 1.0 - row["time_ratio"]
            # seconds of rendering at the compile level after which the run level has repaid its compile
            row["break_even_s"] = row["extra_cold_cpu_s"] / saved if saved > 0 else float("inf")
        rows.append(row)
    return rows


def main() -> int:
    if sys.argv[1:2] == ["--child"]:
        return child_main(sys.argv[2:])
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=list(DEFAULT_SCENES))
    parser.add_argument("--size", default="320x180")
    parser.add_argument("--cold-repeats", type=int, default=3)
    parser.add_argument("--rate-repeats", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=1.0, help="length of each timed pass")
    parser.add_argument("--chunks", type=int, default=5, help="timed passes per rate measurement (the fastest counts)")
    parser.add_argument("--out", type=Path, default=ROOT / "reports" / "optimize_costs.json")
    args = parser.parse_args()
    from renderer.bench.common import format_table, load_average, log, report_header, write_json

    load_before = load_average()
    cold, rates = [], []
    with tempfile.TemporaryDirectory(prefix="lantern-optimize-costs-") as work:
        caches = {}  # (scene, level) -> the cache directory its last cold start filled
        for repeat in range(max(1, args.cold_repeats)):  # without cold repeats, one untimed start fills the caches
            for scene in args.scenes:
                for level in ("compile", "run"):
                    caches[scene, level] = tempfile.mkdtemp(dir=work)
                    log(f"cold start {repeat + 1}/{max(1, args.cold_repeats)}: {scene} at {level}")
                    report = measure(scene, level, args, caches[scene, level], chunks=0) | {"repeat": repeat}
                    if args.cold_repeats:
                        cold.append(report)
                    log(f"  {report['start_s']:.1f} s")
        for repeat in range(args.rate_repeats):
            for scene in args.scenes:
                for level in ("compile", "run"):
                    log(f"rate {repeat + 1}/{args.rate_repeats}: {scene} at {level}")
                    rates.append(measure(scene, level, args, caches[scene, level], args.chunks) | {"repeat": repeat})
                    log(f"  warm start {rates[-1]['start_s']:.1f} s, {rates[-1]['samples_per_s'] / 1e6:.3f} Msamples/s")
    rows = summarise(cold, rates)
    print(format_table(
        ["scene", "kind", "cold compile s", "cold run s", "cold compile cpu s", "cold run cpu s", "extra cpu s",
         "warm compile s", "warm run s", "Ms/s compile", "Ms/s run", "cpu time run/compile", "break-even s",
         "core us/sample"],
        [[r["scene"], r["geometry"], r.get("cold_start_compile_s", "-"), r.get("cold_start_run_s", "-"),
          r.get("cold_cpu_compile_s", "-"), r.get("cold_cpu_run_s", "-"), r.get("extra_cold_cpu_s", "-"),
          r["warm_start_compile_s"], r["warm_start_run_s"], r["rate_compile"] / 1e6, r["rate_run"] / 1e6,
          r["time_ratio"], r.get("break_even_s", "-"), r["core_s_per_sample"] * 1e6] for r in rows]))
    write_json(args.out, report_header("optimize_costs", False, load_before, size=args.size, seconds=args.seconds,
                                       chunks=args.chunks, scenes=rows, cold=cold, rates=rates))
    print(f"\n{args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

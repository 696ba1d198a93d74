"""Whole-process time against Mitsuba 3: what a user waits for, from the command to the image.

Lantern's `python app.py render cornell_box --size S --spp N --max-depth D --integrator mis` and a
Mitsuba process rendering `mi.cornell_box()` at the same size, spp and depth
(renderer/bench/mitsuba_process.py: its LLVM variant, the same thread count) run one after the
other, alternating, `runs` times each, after one untimed run each that fills Taichi's offline cache
and Dr.Jit's kernel cache (so both are timed as a user's second run is: interpreter start, imports,
scene loading, kernel loading from the caches, rendering, writing the image). Each time is the
wall clock of the whole child process. Each side's own "N spp in T s" line (Lantern's `render`, and
renderer/bench/mitsuba_process.py timing its `mi.render` call) splits its time into the render and
the rest (start-up, scene, kernels, writing the image), so the two are compared apart as well.

Both images are compared with a Mitsuba reference at the same size (many more spp, another seed):
RMSE as the root of the mean squared error over the runs, so the two renderers' speed is read at
the error each reaches.

Target (issue: closer to the hardware): Lantern's median at most WHOLE_PROCESS_TARGET times
Mitsuba's.
"""
from __future__ import annotations

import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from renderer.bench.common import REPO_ROOT, describe_error, log

WHOLE_PROCESS_TARGET = 1.5  # Lantern's whole-process time over Mitsuba's, at most
PROCESS_TIMEOUT_S = 900.0
_RENDER_LINE = re.compile(r"\(([\d.]+) spp in ([\d.]+) s\)")


@dataclass(frozen=True)
class WholeProcessConfig:
    size: int = 256
    spp: int = 256
    max_depth: int = 8
    integrator: str = "mis"
    runs: int = 3  # timed runs of each renderer, alternating (after one untimed run each)
    threads: int = 2  # Mitsuba's threads; Lantern's CPU back-end uses every core (2 here)
    seed: int = 1


def lantern_command(config: WholeProcessConfig, seed: int, out: Path) -> list[str]:
    return [sys.executable, "app.py", "render", "cornell_box", "--size", f"{config.size}x{config.size}",
            "--spp", str(config.spp), "--max-depth", str(config.max_depth), "--integrator", config.integrator,
            "--seed", str(seed), "--out", str(out)]


def mitsuba_command(config: WholeProcessConfig, seed: int, out: Path) -> list[str]:
    return [sys.executable, "-m", "renderer.bench.mitsuba_process", "--size", str(config.size), "--spp",
            str(config.spp), "--max-depth", str(config.max_depth), "--seed", str(seed), "--threads",
            str(config.threads), "--out", str(out)]


def timed_process(command: list[str]) -> tuple[float, subprocess.CompletedProcess]:
    """Wall-clock seconds of the child process, start to exit, and its result."""
    start = time.perf_counter()
    done = subprocess.run(command, cwd=REPO_ROOT, capture_output=True, text=True, timeout=PROCESS_TIMEOUT_S)
    return time.perf_counter() - start, done


def render_seconds(output: str) -> float | None:
    """Lantern's own render time from its last "(N spp in T s)" line, None without one."""
    found = _RENDER_LINE.findall(output)
    return float(found[-1][1]) if found else None


def _failure(name: str, done: subprocess.CompletedProcess) -> str:
    tail = " | ".join((done.stderr or done.stdout or "").strip().splitlines()[-2:])
    return f"{name} exited with {done.returncode}: {tail}"


def compare(config: WholeProcessConfig, reference: np.ndarray, reference_spp: int) -> dict:
    """Time both renderers' processes alternately and read their images' error (see the module
    docstring). `reference`: linear RGB (size, size, 3), row 0 = top."""
    from renderer.output.image_io import read_exr

    sides = {
        "lantern": (lantern_command, ".exr", lambda path: read_exr(path)),
        "mitsuba": (mitsuba_command, ".npy", lambda path: np.load(path)),
    }
    results = {name: {"seconds": [], "squared_errors": [], "render_s": []} for name in sides}
    with tempfile.TemporaryDirectory(prefix="lantern_whole_process_") as tmp:
        for run in range(config.runs + 1):  # run 0 warms the caches, untimed
            for name, (command_of, suffix, read) in sides.items():
                out = Path(tmp) / f"{name}_{run}{suffix}"
                command = command_of(config, config.seed + run, out)
                seconds, done = timed_process(command)
                if done.returncode != 0 or not out.is_file():
                    raise RuntimeError(_failure(name, done))
                if run == 0:
                    results[name]["command"] = " ".join(Path(c).name if c == sys.executable else c for c in command)
                    results[name]["warmup_s"] = seconds
                    continue
                image = np.asarray(read(out), dtype=np.float64)[..., :3]
                results[name]["seconds"].append(seconds)
                results[name]["squared_errors"].append(float(np.mean((image - reference) ** 2)))
                results[name]["render_s"].append(render_seconds(done.stdout + done.stderr))
                log(f"[whole process] run {run}: {name} {seconds:.2f} s")
    for side in results.values():
        side["median_s"] = statistics.median(side["seconds"])
        side["rmse"] = float(np.sqrt(np.mean(side.pop("squared_errors"))))
    for side in results.values():
        renders = [s for s in side.pop("render_s") if s is not None]
        if renders:
            side["render_median_s"] = statistics.median(renders)
            side["outside_render_median_s"] = side["median_s"] - statistics.median(renders)
    ratio = results["lantern"]["median_s"] / results["mitsuba"]["median_s"]
    render_ratio = (results["lantern"]["render_median_s"] / results["mitsuba"]["render_median_s"]
                    if all("render_median_s" in results[n] for n in sides) else None)
    return {"size": config.size, "spp": config.spp, "max_depth": config.max_depth, "integrator": config.integrator,
            "runs": config.runs, "threads": config.threads, "reference_spp": reference_spp, **results,
            "ratio": ratio, "render_ratio": render_ratio, "target_ratio": WHOLE_PROCESS_TARGET,
            "passed": ratio <= WHOLE_PROCESS_TARGET}


def compare_or_note(config: WholeProcessConfig, reference: np.ndarray, reference_spp: int) -> dict:
    """compare(), or {"available": False, "note": why} when a process fails."""
    try:
        return {"available": True, **compare(config, reference, reference_spp)}
    except Exception as error:  # noqa: BLE001 - a failed child is reported, the benchmark goes on
        return {"available": False, "note": describe_error(error)}


def summary_rows(result: dict) -> list[list]:
    """Table rows: renderer, median s, each run, render s, the rest, RMSE, ratio to Mitsuba."""
    rows = []
    for name, label in (("mitsuba", "Mitsuba (process)"), ("lantern", f"Lantern render {result['integrator']}")):
        side = result[name]
        rows.append([label, side["median_s"], " / ".join(f"{s:.2f}" for s in side["seconds"]),
                     side.get("render_median_s", "-"), side.get("outside_render_median_s", "-"), side["rmse"],
                     f"{side['median_s'] / result['mitsuba']['median_s']:.2f}x"])
    return rows


HEADERS = ["renderer", "median s", "runs (s)", "of which render s", "start-up and the rest s", "RMSE",
           "time vs Mitsuba"]


def caption(result: dict) -> str:
    return (f"Whole process, Cornell box {result['size']}x{result['size']}, {result['spp']} spp, max depth "
            f"{result['max_depth']}: each renderer's command from start to exit, alternating, {result['runs']} runs "
            f"each after one warm-up run (caches filled); RMSE against a Mitsuba reference of "
            f"{result['reference_spp']} spp. Target: Lantern at most {result['target_ratio']:g}x Mitsuba's time: "
            f"{'PASS' if result['passed'] else 'FAIL'} ({result['ratio']:.2f}x).")


def whole_process_comparison(config, max_depth: int) -> dict:
    """Lantern's `render` command against a Mitsuba process on the Cornell box, start to exit
    (renderer/bench/whole_process.py), both read against a Mitsuba reference of that size."""
    from renderer.bench.mitsuba_side import mitsuba_reference

    size = config.whole_process_size
    log(f"[whole process] Mitsuba reference {size}x{size}, {config.whole_process_reference_spp} spp ...")
    reference = mitsuba_reference(replace(config, mitsuba_reference_spp=config.whole_process_reference_spp),
                                  (size, size), max_depth)
    whole = WholeProcessConfig(size=size, spp=config.whole_process_spp, max_depth=max_depth,
                                  runs=config.whole_process_runs, threads=config.mitsuba_threads)
    log(f"[whole process] {whole.runs} runs of each command, alternating, after a warm-up run each ...")
    return compare_or_note(whole, reference["image"].astype(np.float64), reference["spp"])


def main(argv=None) -> int:
    """`python -m renderer.bench.whole_process [--runs N]`: this comparison alone, as `bench
    integrators` runs it among its others (the same Mitsuba reference and processes); prints its
    table. Needs the optional `mitsuba` package."""
    import argparse

    from renderer.bench.common import print_table
    from renderer.bench.integrator_config import IntegratorBenchConfig

    parser = argparse.ArgumentParser(description=main.__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=WholeProcessConfig.runs, help="timed runs of each renderer")
    args = parser.parse_args(argv)
    result = whole_process_comparison(replace(IntegratorBenchConfig(), whole_process_runs=args.runs),
                                      WholeProcessConfig.max_depth)
    if not result.get("available"):
        print(f"whole-process comparison not measured: {result.get('note')}", file=sys.stderr)
        return 1
    print_table(HEADERS, summary_rows(result), title=caption(result))
    return 0 if result["passed"] else 2


if __name__ == "__main__":
    sys.exit(main())

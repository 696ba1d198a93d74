"""Fuzzing the readers: damaged copies of the test models and scene files must load and render a
tiny image, or be refused in one line. Never a traceback, a hang, a crash or memory beyond the
budget.

Seeds: tests/data's glTF, GLB, OBJ, MTL and PLY files, the shipped scenes and two small scenes
(tests/fuzz/fuzz_cases.py). Damage: truncation, byte flips, repeated chunks, huge counts and
lengths in glTF JSON, deleted fields, values of the wrong kind, extreme numbers, deleted and
duplicated lines (tests/fuzz/mutations.py). Case i is a pure function of a fixed seed and i, so
a failure names a case that can be run again.

The cases run in a worker process (tests/fuzz/fuzz_worker.py) under a memory budget: cases
LANTERN_FUZZ_FIRST (0 by default) up to LANTERN_FUZZ_FIRST + LANTERN_FUZZ_CASES (1,000 by default;
set other ranges to search further), and the first case of each kind of input (a model format,
or one of the small scenes) that loads renders a tiny image too. The same cases run, and the same
of them render, on every machine, however fast or busy. A worker that stops reporting for
WATCHDOG_SECONDS or dies is recorded as a hang or a crash of its case and replaced.
"""
from __future__ import annotations

import json
import os
import selectors
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

from tests.fuzz.fuzz_cases import make_workspace

REPO = Path(__file__).resolve().parents[2]
FIRST = int(os.environ.get("LANTERN_FUZZ_FIRST", "0"))
CASES = int(os.environ.get("LANTERN_FUZZ_CASES", "1000"))
BUDGET = 512 << 20  # what one case's files may ask for
# The kinds of input (fuzz_cases.Case.kind) whose first case to load renders a tiny image (only the
# first of each kind: a new SDF scene compiles its kernels, seconds).
RENDERED_KINDS = {".gltf", ".glb", ".obj", ".mtl", ".ply", "small sdf scene", "small mesh scene"}
WATCHDOG_SECONDS = 45  # longer than a case's own alarm: a case stuck inside native code
CLEAN = ("loaded", "rendered", "refused")


def run_worker(workspace: Path, first: int, end: int, reports: list) -> int:
    """Run cases `first` to `end` - 1, the first of each kind that loads (of the kinds no report
    rendered yet) also rendering; returns the next case to run. Appends every outcome, including
    "hang" and "crash" for a case the worker did not finish."""
    rendered = ",".join(sorted({r["kind"] for r in reports if r.get("rendering")}))
    errors = (workspace / f"worker_{first}.err").open("w+")  # a file: a full pipe would stall the worker
    worker = subprocess.Popen(
        [sys.executable, "-m", "tests.fuzz.fuzz_worker", str(workspace), str(first), str(end), str(BUDGET),
         rendered],
        cwd=REPO, stdout=subprocess.PIPE, stderr=errors, text=True)
    selector = selectors.DefaultSelector()
    selector.register(worker.stdout, selectors.EVENT_READ)
    current, next_case = None, first
    while True:
        if not selector.select(timeout=WATCHDOG_SECONDS):
            worker.kill()
            worker.wait()
            reports.append({"case": current, "outcome": "hang", "detail": f"no report for {WATCHDOG_SECONDS} s"})
            return (current if current is not None else next_case) + 1
        line = worker.stdout.readline()
        if not line:  # the worker ended: after its last case, or by dying in a case
            code = worker.wait()
            errors.seek(0)
            stderr = errors.read()
            if current is not None:
                reports.append({"case": current, "outcome": "crash", "detail": f"exit {code}: {stderr[-600:]}"})
                return current + 1
            assert code == 0, stderr[-2000:]
            return next_case
        if not line.startswith("{"):
            continue  # Taichi's banner
        message = json.loads(line)
        if "start" in message:
            current = message["start"]
        else:
            reports.append(message)
            current, next_case = None, message["case"] + 1


def test_damaged_inputs_load_render_or_are_refused_in_one_line(tmp_path, record_property):
    workspace = make_workspace(tmp_path / "workspace")
    start = time.time()
    reports: list[dict] = []
    case, end = FIRST, FIRST + CASES
    while case < end:  # a worker replaced after a hang or a crash goes on with the next case
        case = run_worker(workspace, case, end, reports)
    counts = Counter(r["outcome"] for r in reports)
    worst = max((r.get("grew_mb", 0) for r in reports), default=0)
    summary = (f"fuzz: {len(reports)} cases in {time.time() - start:.0f} s: "
               + ", ".join(f"{n} {outcome}" for outcome, n in counts.most_common())
               + f"; largest resident growth while loading {worst} MiB (budget {BUDGET >> 20} MiB)")
    record_property("fuzz", summary)  # shown at the end of the run (tests/fuzz/conftest.py)
    failures = [r for r in reports if r["outcome"] not in CLEAN]
    assert not failures, "\n".join(f"{r.get('label', r['case'])}: {r['outcome']}: {r.get('detail')}"
                                   for r in failures[:10])
    assert CASES >= 100, "too few cases to mean anything"
    assert [r["case"] for r in reports] == list(range(FIRST, end)), "every case once, in order"
    assert counts["refused"] and (counts["loaded"] + counts["rendered"]) and counts["rendered"]
    rendered = [r["kind"] for r in reports if r.get("rendering")]
    assert len(rendered) == len(set(rendered)) == counts["rendered"] and set(rendered) <= RENDERED_KINDS, rendered
    if FIRST == 0 and CASES >= 400:  # (every kind has loaded by case 356)
        assert set(rendered) == RENDERED_KINDS, rendered

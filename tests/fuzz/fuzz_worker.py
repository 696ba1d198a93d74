"""Runs fuzz cases in-process and reports each outcome as one JSON line on stdout.

    python -m tests.fuzz.fuzz_worker WORKSPACE FIRST_CASE END_CASE BUDGET_BYTES RENDERED_KINDS

Cases FIRST_CASE, FIRST_CASE + 1, ..., END_CASE - 1 run in order; the first case of each kind
(Case.kind: a model format, or one of the small scenes) that loads, and whose seed renders, also
renders a tiny image, unless its kind is in RENDERED_KINDS (comma-separated: the kinds an earlier
worker of the run rendered). Before a case the worker prints {"start": i}; after it, the outcome
("rendering": true where it tried to render). The parent (test_fuzz_inputs.py) kills a worker
that stops talking (a hang) or dies (a crash) and starts another after that case. Which cases
run, and which of them render, is fixed: not a matter of the machine's speed.

Outcomes: "loaded" and "rendered" (clean), "refused" (a one-line SceneError), and the failures:
"traceback" (any other exception, or a SceneError of several lines), "memory" (a MemoryError, or
a load whose resident memory grew beyond the budget), "timeout" (the case's alarm fired).
"""
from __future__ import annotations

import json
import resource
import signal
import sys
import time
import traceback
import warnings
from pathlib import Path

CASE_SECONDS = 20  # one load plus one tiny render with a cold kernel cache fits easily
MEMORY_SLACK = 64 << 20  # resident growth allowed beyond the budget (the interpreter's own churn)
ADDRESS_SPACE = 8 << 30  # a hard cap under everything: Taichi reserves address space, not memory


class CaseTimeout(Exception):
    pass


def _alarm(signum, frame):
    raise CaseTimeout()


def _status_kib(field: str) -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    return 0


def _reset_peak() -> None:
    Path("/proc/self/clear_refs").write_text("5")  # resets VmHWM, the resident high-water mark


def run_case(case, options, render_allowed: bool) -> dict:
    """Load `case` (and render it where allowed and its seed renders); the report of its outcome."""
    from renderer.scene.catalog import load_any
    from renderer.scene.errors import SceneError

    report = {"case": case.index, "label": case.label}
    start = time.perf_counter()
    _reset_peak()
    before = _status_kib("VmRSS") * 1024
    signal.alarm(CASE_SECONDS)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene = load_any(case.path, options)
            if scene.geometry == "mesh" and case.seed.render:
                from renderer.mesh_world import prepare_mesh_scene

                prepare_mesh_scene(scene)
            grew = _status_kib("VmHWM") * 1024 - before
            report["grew_mb"] = round(grew / 2 ** 20, 1)
            if grew > options.budget.limit + MEMORY_SLACK:
                report.update(outcome="memory", detail=f"resident memory grew {grew >> 20} MiB while loading")
                return report
            report["outcome"] = "loaded"
            if render_allowed and case.seed.render:
                from renderer.camera import CameraFrame
                from renderer.renderer import Renderer

                report["rendering"] = True
                renderer = Renderer(scene, (4, 4))
                renderer.render(CameraFrame.from_spec(scene.camera), 1, "depth", seed=1)
                report["outcome"] = "rendered"
    except CaseTimeout:
        report.update(outcome="timeout", detail=f"over {CASE_SECONDS} s")
    except SceneError as error:
        message = str(error)
        bad = "\n" in message or "MemoryError" in message
        report.update(outcome=("memory" if "MemoryError" in message else "traceback") if bad else "refused",
                      detail=message[:300])
    except MemoryError:
        report.update(outcome="memory", detail=traceback.format_exc()[-600:])
    except Exception:  # noqa: BLE001 - what the test is looking for
        report.update(outcome="traceback", detail=traceback.format_exc()[-1200:])
    finally:
        signal.alarm(0)
    report["seconds"] = round(time.perf_counter() - start, 3)
    return report


def main(workspace: str, first: str, end: str, budget: str, rendered_kinds: str) -> int:
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))
    signal.signal(signal.SIGALRM, _alarm)
    from renderer.runtime.arch import init_taichi
    from renderer.scene.limits import MemoryBudget
    from renderer.scene.load_options import LoadOptions
    from tests.fuzz.fuzz_cases import write_case

    init_taichi("cpu")
    options = LoadOptions(MemoryBudget(int(budget), "the fuzz test's budget"))
    rendered = set(filter(None, rendered_kinds.split(",")))
    for index in range(int(first), int(end)):
        case = write_case(Path(workspace), index)
        print(json.dumps({"start": index, "kind": case.kind}), flush=True)
        report = run_case(case, options, case.kind not in rendered)
        report["kind"] = case.kind
        if report.get("rendering"):
            rendered.add(case.kind)
        print(json.dumps(report), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))

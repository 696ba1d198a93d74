"""`python app.py bench startup`: time from process start to the first rendered frame.

Every measurement is a fresh Python process (`python -m renderer.bench.startup --child ...`), so
nothing is imported or compiled beforehand. The parent notes the wall clock just before it
launches the child and passes it along; the child reports wall-clock marks after each phase:

  interpreter   launch -> first line of this module runs (Python start-up, `-m` import)
  import        taichi and the renderer (or viewer) modules
  init          init_taichi("cpu", cache_dir=...)
  scene         load the default scene
  build         Renderer(scene, 960x540): fields, environment map, materials
  first frame   render 1 spp with the scene's integrator and wait for it (compiles the kernels,
                or loads them from Taichi's offline cache)
  next frame    after the measurement: one more 1 spp frame, the render cost alone, so that
                first frame - next 1 spp = kernel compile (cold) or cache load + JIT (warm)

Cold: an empty offline cache (a fresh temporary directory); warm: the same directory again, so
the kernels load from the cache. (Python's own bytecode cache is warm in both.) The viewer is
measured the same way off-screen: viewer.window.ViewerApp with show_window=False, its first
step() (the window's first presented frame, showing a "compiling..." notice on a cold start)
and the first step that shows a rendered image. Then, as a user flying forwards (W held), it
steps MOVING_FRAMES more frames: the median wall time of the last half is the frame time while
moving, which the viewer holds at its 50 ms budget by lowering the internal resolution.

Kernel optimisation levels (renderer.runtime.arch.OPTIMIZE_FOR): the start-up figures use the default,
"compile"; the renderer is also measured cold and warm with "run" (every Taichi IR optimisation),
and the table sets their compile times against their rendering speed (1 spp frames).

Issue targets: warm start to first frame at most 3 s, judged on the viewer's first rendered frame
(the headless renderer's start to a full-size 1 spp image is reported beside it, and judged only
where the viewer cannot run); frame time at most 50 ms while moving in a 960x540 window. Writes
<out_dir>/bench_startup.json.
"""
from __future__ import annotations

import time

_T_MAIN = time.time()  # as early as possible: the child's "module is running" mark

import argparse  # noqa: E402
import json  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

MARKER = "LANTERN-STARTUP "
TARGET_SECONDS = 3.0
TARGET_MOVING_MS = 50.0
MOVING_FRAMES = 60
DEFAULT_SIZE = (960, 540)
CHILD_TIMEOUT = 600.0

# phase name -> (mark it starts at, mark it ends at)
RENDERER_PHASES = {
    "interpreter": ("launch", "main"),
    "import": ("main", "imported"),
    "init": ("imported", "initialised"),
    "scene": ("initialised", "scene_loaded"),
    "build": ("scene_loaded", "built"),
    "first_frame": ("built", "first_frame"),
    "next_frame": ("first_frame", "second_frame"),  # after start-up: rendering alone
}
VIEWER_PHASES = {
    "interpreter": ("launch", "main"),
    "import": ("main", "imported"),
    "init": ("imported", "initialised"),
    "app": ("initialised", "app_built"),
    "first_window_frame": ("app_built", "first_window_frame"),
    "first_frame": ("first_window_frame", "first_frame"),
    "next_frame": ("first_frame", "second_frame"),  # after start-up: one more step()
}


# --- the child ---------------------------------------------------------------------------------

def child_main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="one start-up measurement (run by the startup benchmark)")
    parser.add_argument("--mode", choices=("renderer", "viewer"), default="renderer")
    parser.add_argument("--cache-dir", required=True)
    parser.add_argument("--launched", type=float, required=True, help="parent's time.time() at launch")
    parser.add_argument("--scene", default=None, help="scene name or file (default: the default scene)")
    parser.add_argument("--size", default=f"{DEFAULT_SIZE[0]}x{DEFAULT_SIZE[1]}")
    parser.add_argument("--integrator", default=None)
    parser.add_argument("--optimize", default="compile")
    args = parser.parse_args(argv)
    width, height = (int(v) for v in args.size.lower().split("x"))
    marks = {"launch": args.launched, "main": _T_MAIN}
    result = {"mode": args.mode, "marks": marks, "size": [width, height]}
    try:
        if args.mode == "renderer":
            _child_renderer(args, (width, height), marks, result)
        else:
            _child_viewer(args, (width, height), marks, result)
    except Exception as error:  # noqa: BLE001 - reported to the parent, which decides
        from renderer.bench.common import describe_error

        result["error"] = describe_error(error)
    print(MARKER + json.dumps(result), flush=True)
    return 0


def _child_renderer(args, size, marks, result) -> None:
    import taichi as ti

    from renderer.runtime.arch import init_taichi
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from renderer.scene import load_scene
    from renderer.scene.catalog import DEFAULT_SCENE, resolve_scene

    marks["imported"] = time.time()
    result["arch"] = init_taichi("cpu", cache_dir=args.cache_dir, optimize=args.optimize)
    marks["initialised"] = time.time()
    scene = load_scene(resolve_scene(args.scene or DEFAULT_SCENE))
    marks["scene_loaded"] = time.time()
    renderer = Renderer(scene, size)
    camera = CameraFrame.from_spec(scene.camera)
    marks["built"] = time.time()
    integrator = args.integrator or scene.render.integrator
    renderer.render(camera, 1, integrator)
    ti.sync()
    marks["first_frame"] = time.time()
    spp = renderer.samples_done
    # one more 1 spp frame, not part of start-up: what rendering alone costs, so that
    # first_frame - next_frame is the kernels' compile or cache-load time
    renderer.render(camera, 1, integrator)
    ti.sync()
    marks["second_frame"] = time.time()
    result.update(scene=scene.name, integrator=integrator, spp=spp)


def _child_viewer(args, size, marks, result) -> None:
    from renderer.runtime.arch import init_taichi
    from renderer.scene.catalog import DEFAULT_SCENE, resolve_scene
    from viewer.window import ViewerApp

    marks["imported"] = time.time()
    result["arch"] = init_taichi("cpu", cache_dir=args.cache_dir, optimize=args.optimize)
    marks["initialised"] = time.time()
    app = ViewerApp(resolve_scene(args.scene or DEFAULT_SCENE), size=size, integrator=args.integrator,
                    show_window=False, screenshot_folder=tempfile.gettempdir())
    marks["app_built"] = time.time()
    app.step()
    marks["first_window_frame"] = time.time()
    frames = 1
    while app.renderer.samples_done == 0 and frames < 10:
        app.step()
        frames += 1
    marks["first_frame"] = time.time()
    plan = app.last_plan
    result.update(scene=app.renderer.scene.name, integrator=app.session.integrator, spp=app.renderer.samples_done,
                  frames=frames, first_plan=None if plan is None else {"size": list(plan.size), "spp": plan.spp})
    app.step()  # not part of start-up: what a frame costs once everything is loaded
    marks["second_frame"] = time.time()
    plan = app.last_plan
    result["next_plan"] = None if plan is None else {"size": list(plan.size), "spp": plan.spp}
    _measure_moving(app, result)


def _measure_moving(app, result) -> None:
    """Fly forwards for MOVING_FRAMES frames; the second half, once the resolution control has
    settled, gives the frame time while moving (median) and the internal sizes it chose."""
    from viewer.window import FrameInput

    forwards = FrameInput(held=frozenset({"w"}))
    times, sizes = [], []
    for _ in range(MOVING_FRAMES):
        t0 = time.perf_counter()
        app.step(forwards)
        times.append(time.perf_counter() - t0)
        if app.last_plan is not None:
            sizes.append(list(app.last_plan.size))
    settled = times[MOVING_FRAMES // 2:]
    result["moving"] = {"frames": MOVING_FRAMES, "median_ms": 1000.0 * statistics.median(settled),
                        "p90_ms": 1000.0 * sorted(settled)[int(0.9 * (len(settled) - 1))],
                        "sizes": sizes[MOVING_FRAMES // 2:]}


# --- the parent --------------------------------------------------------------------------------

def measure(mode: str, cache_dir: str | Path, scene: str | None = None, size: tuple[int, int] = DEFAULT_SIZE,
            integrator: str | None = None, timeout: float = CHILD_TIMEOUT, optimize: str = "compile") -> dict:
    """Run one child process and return its phases (seconds) and totals."""
    from renderer.bench.common import run_module

    args = ["--child", "--mode", mode, "--cache-dir", str(cache_dir), "--size", f"{size[0]}x{size[1]}",
            "--optimize", optimize]
    if scene:
        args += ["--scene", str(scene)]
    if integrator:
        args += ["--integrator", integrator]
    launched = time.time()
    args += ["--launched", repr(launched)]
    proc = run_module("renderer.bench.startup", args, timeout)
    exited = time.time()
    return parse_child_output(proc.stdout, proc.stderr, proc.returncode, exited - launched, mode)


def parse_child_output(stdout: str, stderr: str, returncode: int, process_seconds: float, mode: str) -> dict:
    from renderer.bench.common import child_report

    result, error = child_report(stdout, stderr, returncode, MARKER)
    if result is None:
        return {"mode": mode, "error": error, "process_seconds": process_seconds}
    result["process_seconds"] = process_seconds
    result["returncode"] = returncode
    marks = result.get("marks", {})
    phases = VIEWER_PHASES if mode == "viewer" else RENDERER_PHASES
    result["phases"] = {name: marks[b] - marks[a] for name, (a, b) in phases.items() if a in marks and b in marks}
    if "first_frame" in marks:
        result["start_to_first_frame"] = marks["first_frame"] - marks["launch"]
        result["import_and_init"] = marks["initialised"] - marks["launch"]
    if "first_window_frame" in marks:
        result["start_to_first_window_frame"] = marks["first_window_frame"] - marks["launch"]
    return result


def measure_cold_warm(mode: str, warm_runs: int, log=None, **kwargs) -> dict:
    """One cold run on an empty cache directory, then `warm_runs` on the same directory."""
    cache_dir = tempfile.mkdtemp(prefix=f"lantern-startup-{mode}-")
    try:
        if log:
            log(f"{mode} ({kwargs.get('optimize', 'compile')}): cold (empty offline cache {cache_dir}) ...")
        cold = measure(mode, cache_dir, **kwargs)
        warm = []
        for i in range(warm_runs):
            if log:
                log(f"{mode}: warm run {i + 1}/{warm_runs} ...")
            warm.append(measure(mode, cache_dir, **kwargs))
        from renderer.bench.common import dir_bytes

        cache_bytes = dir_bytes(cache_dir)
    finally:
        shutil.rmtree(cache_dir, ignore_errors=True)
    return {"mode": mode, "optimize": kwargs.get("optimize", "compile"), "cold": cold, "warm_runs": warm,
            "warm": summarise(warm), "cache_bytes": cache_bytes}


def summarise(runs: list[dict]) -> dict:
    """Medians over the runs that worked, of every phase and total."""
    ok = [r for r in runs if "error" not in r]
    out = {"runs": len(runs), "ok": len(ok)}
    if not ok:
        out["error"] = runs[0].get("error") if runs else "no runs"
        return out
    for key in ("start_to_first_frame", "start_to_first_window_frame", "import_and_init", "process_seconds"):
        values = [r[key] for r in ok if key in r]
        if values:
            out[key] = statistics.median(values)
    moving = [r["moving"]["median_ms"] for r in ok if "moving" in r]
    if moving:
        out["moving_ms"] = statistics.median(moving)
    names = [name for name in ok[0]["phases"] if all(name in r["phases"] for r in ok)]
    out["phases"] = {name: statistics.median(r["phases"][name] for r in ok) for name in names}
    return out


def _log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def print_report(report: dict) -> None:
    from renderer.bench.common import print_table, verdict

    for entry in report["measurements"]:
        mode = entry["mode"]
        cold, warm = entry["cold"], entry["warm"]
        phases = VIEWER_PHASES if mode == "viewer" else RENDERER_PHASES
        rows = []
        columns = [("cold", cold.get("phases", {}), cold), ("warm (median of %d)" % warm.get("ok", 0),
                                                             warm.get("phases", {}), warm)]
        for name in phases:
            if name != "next_frame":
                rows.append([name] + [f"{p[name]:.2f}" if name in p else "-" for _, p, _ in columns])
        if mode == "viewer":
            rows.append(["= start to window frame"] + [f"{r['start_to_first_window_frame']:.2f}"
                                                       if "start_to_first_window_frame" in r else "-"
                                                       for _, _, r in columns])
        rows.append(["= import + init"] + [f"{r['import_and_init']:.2f}" if "import_and_init" in r else "-"
                                           for _, _, r in columns])
        rows.append(["= start to first frame"] + [f"{r['start_to_first_frame']:.2f}" if "start_to_first_frame" in r
                                                  else "-" for _, _, r in columns])
        rows.append(["process exit"] + [f"{r['process_seconds']:.2f}" if "process_seconds" in r else "-"
                                        for _, _, r in columns])
        if "next_frame" in cold.get("phases", {}):
            label = "(after) next 1 spp frame" if mode == "renderer" else "(after) next step()"
            rows.append([label] + [f"{p['next_frame']:.2f}" if "next_frame" in p else "-" for _, p, _ in columns])
            rows.append(["first - next: kernels"] + [f"{p['first_frame'] - p['next_frame']:.2f}"
                                                     if "next_frame" in p and "first_frame" in p else "-"
                                                     for _, p, _ in columns])
        what = ("viewer (ViewerApp off-screen, first step that shows a rendered image)" if mode == "viewer"
                else "renderer (Renderer + 1 spp render)")
        w, h = report["size"]
        print_table(["phase (s)"] + [c for c, _, _ in columns], rows,
                    title=f"{what}, {report['scene']} {w}x{h}, CPU, kernels optimised for "
                          f"{entry.get('optimize', 'compile')}; cache {entry['cache_bytes'] / 1e6:.1f} MB")
        for label, r in (("cold", cold), ("warm", warm)):
            if "error" in r:
                print(f"  {label}: FAILED: {r['error']}")
        if "warm_runs" in entry and entry["warm_runs"]:
            firsts = [f"{r['start_to_first_frame']:.2f}" for r in entry["warm_runs"] if "start_to_first_frame" in r]
            print(f"  warm runs, start to first frame: {', '.join(firsts)} s")
        if mode == "viewer" and cold.get("first_plan"):
            print(f"  the viewer's first rendered frame: {cold['first_plan']['spp']} spp at "
                  f"{cold['first_plan']['size'][0]}x{cold['first_plan']['size'][1]} after {cold.get('frames')} step() "
                  f"calls; the next step(): {cold['next_plan']['spp']} spp at "
                  f"{cold['next_plan']['size'][0]}x{cold['next_plan']['size'][1]}")
        moving = [r["moving"] for r in entry.get("warm_runs", []) if "moving" in r]
        if moving:
            sizes = sorted({tuple(s) for m in moving for s in m["sizes"]})
            medians = ", ".join("%.0f" % m["median_ms"] for m in moving)
            p90s = ", ".join("%.0f" % m["p90_ms"] for m in moving)
            shown = ", ".join("%dx%d" % size for size in sizes[:6]) + (" ..." if len(sizes) > 6 else "")
            print(f"  moving (W held, {MOVING_FRAMES} frames, second half): median frame {medians} ms, "
                  f"p90 {p90s} ms; internal sizes {shown}")
        print()
    levels = report.get("optimization_levels", [])
    if levels:
        from renderer.bench.common import print_table as table

        rows = [[lv["optimize"], _fmt(lv.get("cold_kernels")), _fmt(lv.get("warm_kernels")), _fmt(lv.get("frame_seconds")),
                 _fmt(lv.get("msamples_per_second"), 3)] for lv in levels]
        table(["optimise for", "cold kernels (s)", "warm kernels (s)", "1 spp frame (s)", "Msamples/s"], rows,
              title=f"Kernel optimisation levels, renderer, {report['scene']} "
                    f"{report['size'][0]}x{report['size'][1]} (kernels = first frame - next frame)")
        print()
    for t in report["targets"]:
        if "moving_ms" in t:
            value = "n/a" if t["moving_ms"] is None else f"{t['moving_ms']:.0f} ms"
            print(f"Target: frame time while moving <= {TARGET_MOVING_MS:g} ms ({t['what']}): {value}  "
                  f"{verdict(bool(t['passed']))}")
            continue
        value = "n/a" if t["seconds"] is None else f"{t['seconds']:.2f} s"
        if not t.get("judged", True):
            print(f"Reported: warm start to a headless image ({t['what']}): {value}  "
                  f"(the target is the viewer's first frame)")
            continue
        print(f"Target: warm start to first frame <= {TARGET_SECONDS:g} s ({t['what']}): {value}  "
              f"{verdict(bool(t['passed']))}")
    if report.get("viewer_note"):
        print(report["viewer_note"])
    print(flush=True)


def _fmt(value, digits: int = 2) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def optimization_level(entry: dict) -> dict:
    """Compile, cache-load and render costs of one renderer measurement's optimisation level."""
    def kernels(phases):
        if "first_frame" in phases and "next_frame" in phases:
            return phases["first_frame"] - phases["next_frame"]
        return None

    warm = entry["warm"].get("phases", {})
    frame = warm.get("next_frame", entry["cold"].get("phases", {}).get("next_frame"))
    width, height = entry["cold"].get("size", DEFAULT_SIZE)
    return {"optimize": entry.get("optimize", "compile"), "cold_kernels": kernels(entry["cold"].get("phases", {})),
            "warm_kernels": kernels(warm), "frame_seconds": frame,
            "msamples_per_second": None if not frame else width * height / frame / 1e6}


def start_up_targets(measurements: list[dict]) -> list[dict]:
    """The target rows of the report.

    A frame is what the window shows: the start-up target is the viewer's first rendered frame.
    The headless renderer's start to a full 960x540 1 spp image (which includes ~1.3 s of pure
    rendering) is reported beside it, and judged only where the viewer could not be measured.
    """
    viewer_measured = any(m["mode"] == "viewer" and "error" not in m["warm"] for m in measurements)
    targets = []
    for entry in measurements:
        value = entry["warm"].get("start_to_first_frame")
        what = ("viewer, first rendered image" if entry["mode"] == "viewer" else "renderer, 1 spp at 960x540")
        judged = entry["mode"] == "viewer" or not viewer_measured
        targets.append({"what": what, "mode": entry["mode"], "seconds": value, "judged": judged,
                        "passed": value is not None and value <= TARGET_SECONDS})
        if entry["mode"] == "viewer":
            moving = entry["warm"].get("moving_ms")
            targets.append({"what": "viewer 960x540, W held", "mode": "viewer", "moving_ms": moving,
                            "passed": moving is not None and moving <= TARGET_MOVING_MS})
    return targets


def run(quick: bool = False, out_dir: Path = Path("reports"), warm_runs: int = 3, with_viewer: bool = True) -> int:
    from renderer.bench.common import load_average, report_header, write_json

    from renderer.scene.catalog import DEFAULT_SCENE

    out_dir = Path(out_dir)
    t_start = time.time()
    load_before = load_average()
    measurements = [measure_cold_warm("renderer", warm_runs, log=_log)]
    # The other optimisation level, for its compile time against its rendering speed.
    full = measure_cold_warm("renderer", 1, log=_log, optimize="run")
    viewer_note = None
    if with_viewer:
        try:
            import viewer.window  # noqa: F401 - only to see whether the viewer is there

            measurements.append(measure_cold_warm("viewer", 1 if quick else warm_runs, log=_log))
            if "error" in measurements[-1]["warm"]:
                viewer_note = ("The off-screen viewer could not be measured (" + measurements[-1]["warm"]["error"]
                               + "); the renderer path stands for it.")
        except ImportError as error:
            viewer_note = f"viewer.window is not importable ({error}); measured the renderer path only."
    else:
        viewer_note = "The viewer was not measured; the renderer path stands for it."

    targets = start_up_targets(measurements)
    levels = [optimization_level(measurements[0]), optimization_level(full)]
    measurements.append(full)
    report = {
        **report_header("startup", quick, load_before, scene=DEFAULT_SCENE, size=list(DEFAULT_SIZE)),
        "target_seconds": TARGET_SECONDS,
        "notes": ("Each run is a fresh Python process. Marks are wall-clock (time.time()) from just before "
                  "the parent launched the process. Cold = empty Taichi offline cache (fresh temp dir via "
                  "init_taichi(cache_dir=...)); warm = same dir again. Python bytecode caches are warm in both."),
        "measurements": measurements,
        "targets": targets,
        "optimization_levels": levels,
        "viewer_note": viewer_note,
        "total_seconds": time.time() - t_start,
    }
    print_report(report)
    path = write_json(out_dir / "bench_startup.json", report)
    print(f"wrote {path}  (total {report['total_seconds']:.0f} s)")
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        sys.exit(child_main(sys.argv[2:]))
    sys.exit(run(quick="--quick" in sys.argv))

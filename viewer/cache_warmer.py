"""`python app.py warm-cache`: compile the viewer's kernels ahead of time, into Taichi's offline cache.

A scene's first image in the viewer waits for its kernels: compiled (5-120 s a combination on a
2-core CPU) or, where Taichi's offline cache has them, loaded (0.1-7 s). What a cache can hold for
the viewer is narrower than it looks, for two reasons in Taichi 1.7 (its
compilation_manager/kernel_compilation_manager.cpp and analysis/gen_offline_cache_key.cpp):

- A kernel's cache key includes the ids of the fields it touches, and those are numbered in the
  order the process created every field before them. A kernel is found again only by a process
  that created the same fields in the same order: a viewer opened on the same scene at the same
  window size, or one that went through the same scenes in the same order before it.
- A process reads the cache's index once, when it first compiles; kernels another process adds
  later are not seen until the next start. So no process beside a running viewer can shorten
  that viewer's switches, and one inside it would hold the GIL through each compile (Taichi's
  code generation does), freezing the window for as long.

So this warms what a viewer opened on a scene does (`app.py view SCENE --size WxH`): each scene in
a process of its own, which opens the viewer off-screen on it exactly as `view` does, shows the
scene's own integrator first (the one a viewer starts with; light-sampling integrators build the
scene's light structures then), then each other integrator, SPPM last (it builds fields of its
own), and writes its kernels to the cache as it exits. A later `view SCENE` at that size starts
warm, and every integrator key there loads its kernels from the cache. Started with
`--integrator X` instead, the viewer creates fields in another order where X builds some of its
own: integrators that build none (path, normals, ...) still load theirs, SPPM compiles four
kernels again (cornell_box at 320x180: 30 kernels warmed, `view --integrator sppm` added 4).
Scenes reached with n / b from another scene have other field ids and compile as before.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Optional

from renderer.integrators import integrator_names

ROOT = Path(__file__).resolve().parents[1]
RESULT_MARK = "LANTERN-WARM "  # the line of a child's results starts with this
FIRST_IMAGE_FRAME_LIMIT = 50  # a switch that has not shown an image after this many frames failed


def step_to_first_image(app, frame_limit: int = FIRST_IMAGE_FRAME_LIMIT) -> dict:
    """Step the viewer until a frame shows a rendered image (frames that only show the 'loading' or
    'compiling' notice come first): the frames it took, how many showed a notice, the longest, and
    whether an image came within `frame_limit` frames."""
    from viewer.window import FrameInput

    frames, notice_frames, longest = 0, 0, 0.0
    while frames < frame_limit:
        t0 = time.perf_counter()
        app.step(FrameInput())
        longest = max(longest, time.perf_counter() - t0)
        frames += 1
        if app.notice:
            notice_frames += 1
        elif app.last_plan is not None and app.renderer.slices_done > 0:
            return {"frames": frames, "notice_frames": notice_frames, "longest_frame_s": longest, "shown": True}
    return {"frames": frames, "notice_frames": notice_frames, "longest_frame_s": longest, "shown": False}


def warm_order(first: str, integrators: list[str]) -> list[str]:
    """The order a scene's integrators are shown in: the viewer's first one, then the others as
    listed, SPPM last (the only one that builds fields of its own, after which nothing else does)."""
    rest = [name for name in integrators if name != first]
    return ([first] if first in integrators else []) + [n for n in rest if n != "sppm"] + [n for n in rest if n == "sppm"]


def warm_scene(scene_path: Path, size: tuple[int, int], integrators: list[str], packets: int = 0) -> list[dict]:
    """In this process (Taichi initialised as the viewer does it): open the viewer off-screen on
    the scene (with `view --packets` rays a packet) and show each integrator's first image; what
    each took."""
    from viewer.window import ViewerApp

    with tempfile.TemporaryDirectory() as shots:
        app = ViewerApp(scene_path, size=size, show_window=False, screenshot_folder=shots, packets=packets)
        results = []
        for integrator in warm_order(app.session.integrator, integrators):
            t0 = time.perf_counter()
            app.session.set_integrator(integrator)
            app.compile_seconds = None
            shown = step_to_first_image(app)
            results.append({"scene": scene_path.stem, "integrator": integrator, "compile_s": app.compile_seconds,
                            "first_image_s": time.perf_counter() - t0, "shown": shown["shown"]})
        return results


def _child(argv: list[str]) -> int:
    """`python -m viewer.cache_warmer SCENE WxH INTEGRATORS ARCH PACKETS`: warm one scene, print its results."""
    scene, size, integrators, arch, packets = argv
    from renderer.runtime.arch import init_taichi

    init_taichi(arch, optimize="compile")  # as `app.py view` does
    width, height = (int(v) for v in size.split("x"))
    combinations = warm_scene(Path(scene), (width, height), integrators.split(","), int(packets))
    print(RESULT_MARK + json.dumps({"combinations": combinations}), flush=True)
    return 0


def cached_kernels(cache_dir: Path) -> int:
    """Kernels in a Taichi offline cache folder (a file each, named by its key)."""
    return sum(1 for _ in Path(cache_dir).glob("*.tic"))


def warm_scenes(scene_paths: list[Path], size: tuple[int, int], integrators: Optional[list[str]] = None,
                arch: str = "cpu", timeout_s: float = 3600.0, report=print, packets: int = 0) -> list[dict]:
    """Warm each scene in a child process of its own (its kernels reach the cache when it exits);
    `report(line)` is told each scene's combinations as its child ends, with the kernels it added
    to the cache (0: every one was there already). A scene whose child fails is reported with
    its error and the others go on."""
    from renderer.runtime.arch import default_cache_dir
    from renderer.bench.common import child_report

    cache_dir = Path(default_cache_dir())
    integrators = integrators or integrator_names()
    results = []
    for path in scene_paths:
        command = [sys.executable, "-m", "viewer.cache_warmer", str(path), f"{size[0]}x{size[1]}",
                   ",".join(integrators), arch, str(packets)]
        before, started = cached_kernels(cache_dir), time.perf_counter()
        try:
            done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=timeout_s)
            result, why = child_report(done.stdout, done.stderr, done.returncode, RESULT_MARK)
            lines, error = ([], why) if result is None else (result["combinations"], None)
        except subprocess.TimeoutExpired:
            lines, error = [], f"not done after {timeout_s:.0f} s"
        added, seconds = cached_kernels(cache_dir) - before, time.perf_counter() - started
        for line in lines:
            report(_result_text(line))
        if error is None:
            report(f"{path.stem}: {added} kernels added to the cache ({seconds:.0f} s)")
        else:
            report(f"{path.stem}: failed: {error}")
        results.append({"scene": path.stem, "combinations": lines, "kernels_added": added, "seconds": seconds,
                        "error": error})
    return results


def _result_text(result: dict) -> str:
    compiled = result["compile_s"]
    kernels = "compiled earlier in this process" if compiled is None else f"kernels ready in {compiled:.1f} s"
    shown = "" if result["shown"] else " (no image shown)"
    return f"  {result['scene']} / {result['integrator']}: {kernels}, first image {result['first_image_s']:.1f} s{shown}"


if __name__ == "__main__":
    sys.exit(_child(sys.argv[1:]))

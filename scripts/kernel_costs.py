"""Where a start goes, kernel by kernel: for one scene, build the Renderer and render 1 spp twice,
timing every Taichi kernel's launches and, for the first launch of each, the Python-side building
of its IR (Taichi transforms every `ti.func` again at each call site) apart from the rest (offline
cache lookup, LLVM, and the run itself).

    python scripts/kernel_costs.py [SCENE] [--integrator NAME] [--size WxH] [--cache-dir DIR]

Run it twice with the same cache directory: the first run compiles, the second shows a warm start.
"""
import argparse
import sys
import time
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=None)
    parser.add_argument("--integrator", default=None)
    parser.add_argument("--size", default="960x540")
    parser.add_argument("--cache-dir", default=None)
    args = parser.parse_args()

    import taichi as ti
    from taichi.lang import kernel_impl

    built = defaultdict(float)  # kernel name -> seconds building IR (materialize)
    total = defaultdict(float)  # kernel name -> seconds in all its launches (build included)
    calls = defaultdict(int)
    materialize, call = kernel_impl.Kernel.materialize, kernel_impl.Kernel.__call__

    def timed_materialize(self, *a, **k):
        t = time.perf_counter()
        try:
            return materialize(self, *a, **k)
        finally:
            built[self.func.__name__] += time.perf_counter() - t

    def timed_call(self, *a, **k):
        t = time.perf_counter()
        try:
            return call(self, *a, **k)
        finally:
            ti.sync()
            total[self.func.__name__] += time.perf_counter() - t
            calls[self.func.__name__] += 1

    kernel_impl.Kernel.materialize, kernel_impl.Kernel.__call__ = timed_materialize, timed_call

    from renderer.runtime.arch import init_taichi
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from renderer.scene import load_scene
    from renderer.scene.catalog import DEFAULT_SCENE, resolve_scene

    init_taichi("cpu", cache_dir=args.cache_dir)
    scene = load_scene(resolve_scene(args.scene or DEFAULT_SCENE))
    width, height = (int(v) for v in args.size.split("x"))
    marks = [("start", time.perf_counter())]
    renderer = Renderer(scene, (width, height))
    marks.append(("Renderer built", time.perf_counter()))
    camera = CameraFrame.from_spec(scene.camera)
    for label in ("first 1 spp", "second 1 spp"):
        renderer.render(camera, 1, args.integrator)
        ti.sync()
        marks.append((label, time.perf_counter()))
    for (_, a), (label, b) in zip(marks, marks[1:]):
        print(f"{label:16s} {b - a:7.3f} s")
    print(f"\n{'kernel':32s} {'launches':>8s} {'all (s)':>8s} {'IR build (s)':>12s}")
    for name in sorted(total, key=total.get, reverse=True):
        print(f"{name:32s} {calls[name]:8d} {total[name]:8.3f} {built[name]:12.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""What spreading a pass's loop over the CPU's threads buys (renderer/spread_loop.py): the render
kernel with and without it, built twice in one process and alternated, so a drift of the machine's
speed hits both.

    python scripts/spread_loop_cost.py [rounds] [scene/integrator ...]

For each case, a round (a sample per pixel) at 960x540 in passes of 1 slice and of 12 slices (a
viewer still frame's, bands of rows) and in one whole-round launch (raster order): ms per slice
of each, and the paired median of plain / spread (above 1: spreading is faster).
"""
import copy
import statistics
import sys
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZE = (960, 540)
DEFAULT_CASES = ("cornell_box/mis", "bunnies/mis", "textured/mis", "showcase/mis")
PASSES = (1, 12, 256)


def round_ms_per_slice(program, args, slices_per_pass: int) -> float:
    import time

    import taichi as ti

    from renderer.pixel_slices import BANDS, INTERLEAVED, ROUND_SLICES

    order = INTERLEAVED if slices_per_pass >= ROUND_SLICES else BANDS
    start = time.perf_counter()
    for first in range(0, ROUND_SLICES, slices_per_pass):
        program.render(*SIZE, 1, first, min(slices_per_pass, ROUND_SLICES - first), order, *args)
        ti.sync()
    return (time.perf_counter() - start) / ROUND_SLICES * 1e3


def measure(case: str, rounds: int) -> list[str]:
    import taichi as ti

    from renderer.bench.common import load_named_scene
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    name, integrator = case.split("/")
    scene = load_named_scene(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        renderer = Renderer(scene, SIZE)
    camera = CameraFrame.from_spec(scene.camera)
    renderer.render(camera, 1, integrator)
    ti.sync()
    spread = renderer.program(integrator, renderer.features(camera), scene.render.sampler)
    if not spread.spread:
        raise SystemExit("this back-end does not spread loops (CPU only)")
    plain = copy.copy(spread)  # another instance: Taichi compiles its kernels again, with spread off
    plain.spread = False
    args = (scene.render.seed, scene.render.max_depth, *camera.kernel_args())
    times = {(k, p): [] for k in PASSES for p in ("spread", "plain")}
    for _ in range(rounds):
        for k in PASSES:
            times[(k, "spread")].append(round_ms_per_slice(spread, args, k))
            times[(k, "plain")].append(round_ms_per_slice(plain, args, k))
    lines = []
    for k in PASSES:
        a, b = times[(k, "spread")], times[(k, "plain")]
        paired = statistics.median(y / x for x, y in zip(a, b))
        lines.append(f"{case}: passes of {k:3d} slices: spread {statistics.median(a):.2f}, plain "
                     f"{statistics.median(b):.2f} ms a slice; plain / spread {paired:.3f} (paired)")
    return lines


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(ROOT))
    from renderer.arch import init_taichi

    rounds = int(argv[0]) if argv and argv[0].isdigit() else 3
    cases = [a for a in argv if not a.isdigit()] or list(DEFAULT_CASES)
    init_taichi("cpu")
    for case in cases:
        for line in measure(case, rounds):
            print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

"""What a viewer still frame's passes cost per slice: whole rounds against passes of one frame's
slices in the interleaved and the banded order (renderer/film/pixel_slices.py), alternated in one
process so a drift of the machine's speed hits all three.

    python scripts/slice_order_cost.py [rounds] [scene/integrator ...]

The pass size is the slices one FRAME_SECONDS frame renders at the scene's whole-round cost.
Prints, per scene, each order's time for a round relative to a whole-round launch (median over
the rounds) and the paired ratio interleaved / bands.
"""
import statistics
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FRAME_SECONDS = 0.040  # the viewer's render budget of a 45 ms frame, roughly
SIZE = (960, 540)  # the viewer's default window
DEFAULT_CASES = ("cornell_box/path", "bunnies/mis", "textured/mis", "showcase/path", "pool/mis")


def round_seconds(program, args, order: int, slices_per_pass: int) -> float:
    """Seconds to render one round (a sample per pixel) in passes of `slices_per_pass` slices."""
    import taichi as ti

    from renderer.film.pixel_slices import ROUND_SLICES

    start = time.perf_counter()
    for first in range(0, ROUND_SLICES, slices_per_pass):
        program.render(*SIZE, 1, first, min(slices_per_pass, ROUND_SLICES - first), order, *args)
        ti.sync()
    return time.perf_counter() - start


def frame_slices(whole_round_seconds: float) -> int:
    """Slices one FRAME_SECONDS still frame renders at a scene's whole-round cost (1 to a round less one)."""
    from renderer.film.pixel_slices import ROUND_SLICES

    return max(1, min(ROUND_SLICES - 1, round(FRAME_SECONDS / (whole_round_seconds / ROUND_SLICES))))


def compiled(case: str):
    """(program, its render arguments after the pass's own) of "scene/integrator" at SIZE, compiled,
    with the viewer's Renderer (AOVs kept)."""
    import taichi as ti

    from renderer.bench.common import load_named_scene
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    name, integrator = case.split("/")
    scene = load_named_scene(name)
    renderer = Renderer(scene, SIZE, aovs=True)
    camera = CameraFrame.from_spec(scene.camera)
    renderer.render(camera, 1, integrator)  # compiles
    ti.sync()
    program, seed, max_depth = renderer._launch(camera, integrator, None, None, None, None)
    return program, (seed, max_depth, *camera.kernel_args())


def measure(case: str, rounds: int) -> str:
    from renderer.film.pixel_slices import BANDS, INTERLEAVED, ROUND_SLICES

    program, args = compiled(case)
    whole = round_seconds(program, args, INTERLEAVED, ROUND_SLICES)
    per_pass = frame_slices(whole)
    times = {"whole": [], "interleaved": [], "bands": []}
    for _ in range(rounds):
        times["whole"].append(round_seconds(program, args, INTERLEAVED, ROUND_SLICES))
        times["interleaved"].append(round_seconds(program, args, INTERLEAVED, per_pass))
        times["bands"].append(round_seconds(program, args, BANDS, per_pass))
    base = statistics.median(times["whole"])
    paired = statistics.median(i / b for i, b in zip(times["interleaved"], times["bands"]))
    return (f"{case}: {per_pass} slices a pass; a round in passes, relative to whole-round launches "
            f"({1000 * base:.0f} ms): interleaved {statistics.median(times['interleaved']) / base:.3f}, "
            f"bands {statistics.median(times['bands']) / base:.3f}; interleaved / bands {paired:.3f} (paired)")


def main() -> None:
    sys.path.insert(0, str(ROOT))
    from renderer.runtime.arch import init_taichi

    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    cases = sys.argv[2:] or DEFAULT_CASES
    init_taichi("cpu")
    warnings.simplefilter("ignore")
    for case in cases:
        print(measure(case, rounds), flush=True)


if __name__ == "__main__":
    main()

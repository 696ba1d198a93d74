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

from slice_order_cost import ROOT, compiled, round_seconds  # the same passes, at the viewer's SIZE

DEFAULT_CASES = ("cornell_box/mis", "bunnies/mis", "textured/mis", "showcase/mis")
PASSES = (1, 12, 256)


def measure(case: str, rounds: int) -> list[str]:
    from renderer.pixel_slices import BANDS, INTERLEAVED, ROUND_SLICES

    spread, args = compiled(case)
    if not spread.spread:
        raise SystemExit("this back-end does not spread loops (CPU only)")
    plain = copy.copy(spread)  # another instance: Taichi compiles its kernels again, with spread off
    plain.spread = False
    round_seconds(plain, args, BANDS, ROUND_SLICES - 1)  # compiles it outside the timings
    times = {(k, p): [] for k in PASSES for p in ("spread", "plain")}
    for _ in range(rounds):
        for k in PASSES:
            order = INTERLEAVED if k >= ROUND_SLICES else BANDS
            for name, program in (("spread", spread), ("plain", plain)):
                times[(k, name)].append(round_seconds(program, args, order, k) / ROUND_SLICES * 1e3)
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
    warnings.simplefilter("ignore")
    for case in cases:
        for line in measure(case, rounds):
            print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

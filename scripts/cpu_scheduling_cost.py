"""What sharing a parallel loop's blocks among the CPU's threads as they finish buys
(renderer/arch.cpu_scheduling_options) against Taichi's default of one contiguous share of the
loop per thread: the render kernel compiled under each setting in one process (the setting is
read when a kernel compiles; the offline cache is off, as its key leaves the setting out), and the
two alternated, so a drift of the machine's speed hits both.

    python scripts/cpu_scheduling_cost.py [rounds] [scene/integrator ...]

Per case: a round (a sample per pixel) at 960x540 as one whole-round launch (raster order), in
passes of 4 slices, and in passes of one viewer still frame's slices (bands of rows, as the
viewer renders them after the first round); ms per slice under each setting (median over the
rounds) and the paired median static / dynamic (above 1: dynamic is faster).
"""
import statistics
import sys
import warnings

from slice_order_cost import FRAME_SECONDS, ROOT, compiled, round_seconds

DEFAULT_CASES = ("cornell_box/mis", "bunnies/mis", "textured/mis", "showcase/mis")


def compiled_under(case: str, dynamic: bool):
    """compiled(case), its kernels compiled with the dynamic or the static sharing of loops."""
    import taichi as ti

    config = ti.lang.impl.current_cfg()
    before = config.make_cpu_multithreading_loop
    config.make_cpu_multithreading_loop = not dynamic  # Taichi's rewrite into one share per thread
    try:
        return compiled(case)
    finally:
        config.make_cpu_multithreading_loop = before


def measure(case: str, rounds: int) -> list[str]:
    from renderer.pixel_slices import BANDS, INTERLEAVED, ROUND_SLICES

    programs = {"static": compiled_under(case, False), "dynamic": compiled_under(case, True)}
    whole = round_seconds(*programs["static"], INTERLEAVED, ROUND_SLICES)
    frame = max(1, min(ROUND_SLICES - 1, round(FRAME_SECONDS / (whole / ROUND_SLICES))))
    passes = {"whole round": (INTERLEAVED, ROUND_SLICES), "passes of 4 slices": (BANDS, 4),
              f"passes of a frame ({frame} slices)": (BANDS, frame)}
    times = {(kind, name): [] for kind in passes for name in programs}
    for _ in range(rounds):
        for kind, (order, slices) in passes.items():
            for name, (program, args) in programs.items():
                times[(kind, name)].append(round_seconds(program, args, order, slices) / ROUND_SLICES * 1e3)
    lines = []
    for kind in passes:
        static, dynamic = times[(kind, "static")], times[(kind, "dynamic")]
        paired = statistics.median(s / d for s, d in zip(static, dynamic))
        lines.append(f"{case}: {kind}: static {statistics.median(static):.2f}, dynamic "
                     f"{statistics.median(dynamic):.2f} ms a slice; static / dynamic {paired:.3f} (paired)")
    return lines


def main(argv: list[str]) -> int:
    sys.path.insert(0, str(ROOT))
    from renderer.arch import init_taichi

    rounds = int(argv[0]) if argv and argv[0].isdigit() else 5
    cases = [a for a in argv if not a.isdigit()] or list(DEFAULT_CASES)
    init_taichi("cpu", offline_cache=False)  # Taichi's cache key leaves the setting out (renderer/arch.py)
    warnings.simplefilter("ignore")
    for case in cases:
        for line in measure(case, rounds):
            print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

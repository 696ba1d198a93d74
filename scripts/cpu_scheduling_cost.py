"""What sharing a parallel loop's blocks among the CPU's threads as they finish buys
(renderer/arch.cpu_scheduling_options) against Taichi's default of one contiguous share of the
loop per thread: the render kernel compiled under each setting in one process (the setting is
read when a kernel compiles; the offline cache is off, as its key leaves the setting out), and the
two alternated, so a drift of the machine's speed hits both.

    python scripts/cpu_scheduling_cost.py [rounds] [scene/integrator ...]

First, two facts of Taichi 1.7.4 the setting rests on: a loop of N busy iterations (each the
same work) takes as long under the static shares as on one thread while N is a few hundred, and
a kernel compiled under one setting into the offline cache is loaded as it is under the other
(the cache key leaves the setting out; child processes sharing a fresh cache folder).

Per case: a round (a sample per pixel) at 960x540 as one whole-round launch (raster order), in
passes of 4 slices, and in passes of one viewer still frame's slices (bands of rows, as the
viewer renders them after the first round); ms per slice under each setting (median over the
rounds) and the paired median static / dynamic (above 1: dynamic is faster).
"""
import statistics
import subprocess
import sys
import tempfile
import time
import warnings

from slice_order_cost import ROOT, compiled, frame_slices, round_seconds

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


BUSY_WORK = 20_000_000  # sin() steps shared among a loop's iterations


def busy_kernel(dynamic: bool):
    """A kernel whose loop of n iterations shares `work` sin() steps (BUSY_WORK unless given; the
    first `busy` iterations only), compiled under the given setting; returns a callable
    (n, busy, work=BUSY_WORK) -> seconds of one launch (n at most 4,096)."""
    import taichi as ti

    out = ti.field(ti.f32, shape=4096)

    @ti.kernel
    def busy_loop(n: ti.i32, busy: ti.i32, steps: ti.i32):
        for k in range(n):
            acc = 0.0
            if k < busy:
                for j in range(steps):
                    acc = ti.sin(acc + j * 1e-3)
            out[k] = acc

    config = ti.lang.impl.current_cfg()
    before = config.make_cpu_multithreading_loop
    config.make_cpu_multithreading_loop = not dynamic
    try:
        busy_loop(2, 2, 1)  # compiles under the setting
    finally:
        config.make_cpu_multithreading_loop = before

    def seconds(n: int, busy: int, work: int = BUSY_WORK) -> float:
        start = time.perf_counter()
        busy_loop(n, busy, work // busy)
        ti.sync()
        return time.perf_counter() - start

    return seconds


def loop_size_lines() -> list[str]:
    static, dynamic = busy_kernel(False), busy_kernel(True)
    return [f"a loop of {n} busy iterations: static {static(n, n):.3f} s, dynamic {dynamic(n, n):.3f} s"
            for n in (2, 256, 1024, 4096)]


def cache_child(folder: str, dynamic: bool) -> None:
    """Print the seconds of an uneven loop (4,096 iterations, the first half busy) compiled or
    loaded through the offline cache in `folder` under the given setting."""
    import taichi as ti

    ti.init(arch=ti.cpu, log_level=ti.WARN, offline_cache=True, offline_cache_file_path=folder,
            make_cpu_multithreading_loop=not dynamic)
    seconds = busy_kernel(dynamic)
    seconds(4096, 2048)
    print(seconds(4096, 2048))


def cache_key_lines() -> list[str]:
    def child(folder: str, mode: str) -> float:
        out = subprocess.run([sys.executable, __file__, "--cache-child", folder, mode], capture_output=True,
                             text=True, check=True)
        return float(out.stdout.strip().splitlines()[-1])

    with tempfile.TemporaryDirectory() as shared, tempfile.TemporaryDirectory() as fresh:
        static_compiled = child(shared, "static")
        dynamic_loaded = child(shared, "dynamic")  # the static kernel, from the cache
        dynamic_compiled = child(fresh, "dynamic")
    return [f"an uneven loop: static {static_compiled:.3f} s; dynamic compiled afresh {dynamic_compiled:.3f} s; "
            f"dynamic loaded from a cache the static run filled {dynamic_loaded:.3f} s"]


def measure(case: str, rounds: int) -> list[str]:
    from renderer.film.pixel_slices import BANDS, INTERLEAVED, ROUND_SLICES

    programs = {"static": compiled_under(case, False), "dynamic": compiled_under(case, True)}
    whole = round_seconds(*programs["static"], INTERLEAVED, ROUND_SLICES)
    frame = frame_slices(whole)
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
    if argv[:1] == ["--cache-child"]:
        cache_child(argv[1], argv[2] == "dynamic")
        return 0
    for line in cache_key_lines():
        print(line, flush=True)
    sys.path.insert(0, str(ROOT))
    from renderer.runtime.arch import init_taichi

    rounds = int(argv[0]) if argv and argv[0].isdigit() else 5
    cases = [a for a in argv if not a.isdigit()] or list(DEFAULT_CASES)
    init_taichi("cpu", offline_cache=False)  # Taichi's cache key leaves the setting out (renderer/runtime/arch.py)
    warnings.simplefilter("ignore")
    for line in loop_size_lines():
        print(line, flush=True)
    for case in cases:
        for line in measure(case, rounds):
            print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

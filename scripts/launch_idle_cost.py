"""Where a viewer still frame's passes lose time against a whole round: the CPU threads' own
accounts (Linux's per-thread schedstat: time run, time waiting runnable for a CPU), per launch.

    python scripts/launch_idle_cost.py [rounds] [scene/integrator ...]

Per case: a round (a sample per pixel) at 960x540 as one whole-round launch and in passes of
one still frame's slices (bands, as the viewer renders them after the first round), Taichi's
pool threads free (the OS places them) and pinned one per CPU, alternated. Per round: wall time,
the pool threads' run time, their time waiting runnable, and their idle time (threads x wall -
run: asleep, or not yet woken, while the launch ran), then the passes' extra wall time per
launch; and what a launch of no pixels costs (the calling thread's share of every launch).

Taichi 1.7.4's CPU back-end runs a parallel loop on its own pool threads (the calling thread only
waits); a thread asleep between launches has to be woken for the next one. Figures: medians
over `rounds`.
"""
import os
import statistics
import sys
import threading
import time
import warnings

from slice_order_cost import ROOT, SIZE, compiled, frame_slices, round_seconds

DEFAULT_CASES = ("cornell_box/mis", "textured/mis")
EMPTY_LAUNCHES = 200


def thread_times() -> dict[int, tuple[int, int]]:
    """{thread id: (ns run, ns waiting runnable)} of this process's threads (Linux schedstat)."""
    times = {}
    for name in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{name}/schedstat") as f:
                run, wait = f.read().split()[:2]
        except OSError:
            continue
        times[int(name)] = (int(run), int(wait))
    return times


def pool_threads(launch, count: int) -> list[int]:
    """The `count` threads other than this one that ran most during `launch()`: Taichi's pool."""
    before = thread_times()
    launch()
    after = thread_times()
    me = threading.get_native_id()
    grew = sorted(((after[t][0] - before.get(t, (0, 0))[0], t) for t in after if t != me), reverse=True)
    return [t for ran, t in grew[:count] if ran > 0]


def pin(threads: list[int], pinned: bool) -> None:
    """Pin thread k to the k-th CPU this process may use, or let it run on any of them."""
    cpus = sorted(os.sched_getaffinity(0))
    for k, thread in enumerate(threads):
        os.sched_setaffinity(thread, {cpus[k % len(cpus)]} if pinned else set(cpus))


def accounted(threads: list[int], work) -> dict:
    """Wall seconds of work() and the pool threads' run, runnable-wait and idle seconds meanwhile."""
    before = thread_times()
    start = time.perf_counter()
    work()
    wall = time.perf_counter() - start
    after = thread_times()
    run = sum(after[t][0] - before[t][0] for t in threads) / 1e9
    wait = sum(after[t][1] - before[t][1] for t in threads) / 1e9
    return {"wall": wall, "run": run, "wait": wait, "idle": len(threads) * wall - run}


def case_lines(case: str, rounds: int, threads: int) -> list[str]:
    from renderer.film.pixel_slices import BANDS, INTERLEAVED, ROUND_SLICES

    program, args = compiled(case)
    workers = pool_threads(lambda: round_seconds(program, args, INTERLEAVED, ROUND_SLICES), threads)
    whole = round_seconds(program, args, INTERLEAVED, ROUND_SLICES)
    frame = frame_slices(whole)
    launches = -(-ROUND_SLICES // frame)
    kinds = {"whole round": (INTERLEAVED, ROUND_SLICES), f"passes of {frame} slices": (BANDS, frame)}
    runs = {(kind, pinned): [] for kind in kinds for pinned in (False, True)}
    for r in range(rounds):
        for pinned in ((False, True) if r % 2 == 0 else (True, False)):
            pin(workers, pinned)
            for kind, (order, slices) in kinds.items():
                runs[(kind, pinned)].append(accounted(workers, lambda: round_seconds(program, args, order, slices)))
    pin(workers, False)
    empty = accounted(workers, lambda: [program.render(*SIZE, 1, 0, 0, BANDS, *args) for _ in range(EMPTY_LAUNCHES)])
    lines = [f"{case}: an empty launch (no pixels): {empty['wall'] / EMPTY_LAUNCHES * 1e3:.2f} ms, the pool's threads "
             f"running {empty['run'] / EMPTY_LAUNCHES * 1e3:.3f} ms of it"]
    for pinned in (False, True):
        label = "pinned" if pinned else "free"
        summary = {kind: {key: statistics.median(g[key] for g in runs[(kind, pinned)]) * 1e3
                          for key in ("wall", "run", "wait", "idle")} for kind in kinds}
        for kind, s in summary.items():
            lines.append(f"{case}, {label}, {kind}: wall {s['wall']:.0f} ms, workers ran {s['run']:.0f}, waited "
                         f"runnable {s['wait']:.1f}, idle {s['idle']:.1f} ms")
        whole_s, passes_s = (summary[kind] for kind in kinds)
        lines.append(f"{case}, {label}: the passes' extra per launch ({launches} launches): wall "
                     f"{(passes_s['wall'] - whole_s['wall']) / launches:.2f} ms, workers' run "
                     f"{(passes_s['run'] - whole_s['run']) / launches:.2f}, idle "
                     f"{(passes_s['idle'] - whole_s['idle']) / launches:.2f} ms; whole / passes wall "
                     f"{statistics.median(w['wall'] / p['wall'] for w, p in zip(*(runs[(k, pinned)] for k in kinds))):.3f}"
                     " (paired)")
    return lines


def main(argv: list[str]) -> int:
    if not os.path.exists("/proc/self/task") or not hasattr(os, "sched_setaffinity"):
        print("needs Linux's per-thread schedstat (/proc/self/task/*/schedstat) and sched_setaffinity")
        return 1
    sys.path.insert(0, str(ROOT))
    import taichi as ti

    from renderer.runtime.arch import init_taichi

    rounds = int(argv[0]) if argv and argv[0].isdigit() else 5
    cases = [a for a in argv if not a.isdigit()] or list(DEFAULT_CASES)
    init_taichi("cpu")
    warnings.simplefilter("ignore")
    threads = ti.lang.impl.current_cfg().cpu_max_num_threads
    print(f"{threads} pool threads, {len(os.sched_getaffinity(0))} CPUs; {SIZE[0]}x{SIZE[1]}", flush=True)
    for case in cases:
        for line in case_lines(case, rounds, threads):
            print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

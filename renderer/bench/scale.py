"""`python app.py bench scale`: what distributing a render over Ray workers gains, and what a chunk costs.

On this machine, one scene (cornell_box, `mis`), the same image rendered:
1. in one process with every core (two threads here): the baseline, its rate after compiling;
2. on 1 and on 2 local Ray workers of one thread each (renderer/commands/distributed/), chunks sized by the
   default rule (about 2 s of work each);
3. on 2 workers with one-sample chunks: the overhead of a chunk when it is smallest.

For each: samples/s after compilation (the workers' summed rates), wall time with start-up, speed-up
and efficiency against the baseline, bytes of pixel state moved per chunk, and a chunk's overhead:
its round trip (state gathered, sent, rendered, returned, merged) minus its render time, in ms and
against the render time. The images must be bit-identical to the baseline's (checked). The chunk
size rule follows: a chunk renders at least 20x its overhead for the overhead to stay under 5%.

Writes <out_dir>/bench_scale.json and bench_scale.png.
"""
from __future__ import annotations

import statistics
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from renderer.bench.common import load_average, load_named_scene, log, print_table, pyplot, report_header, \
    save_figure, write_json

OVERHEAD_TARGET = 0.05  # a chunk's overhead against its render time


@dataclass(frozen=True)
class ScaleBenchConfig:
    scene: str = "cornell_box"
    size: tuple[int, int] = (320, 180)
    spp: int = 128
    integrator: str = "mis"
    seed: int = 3
    # (workers, chunk spp or None for the default sizer) of each distributed run
    distributed_runs: tuple[tuple[int, int | None], ...] = ((1, None), (2, None), (2, 1))


FULL = ScaleBenchConfig()
QUICK = ScaleBenchConfig(size=(96, 54), spp=8)


def one_process(scene, job) -> dict:
    """The baseline: this process, every core; the rate after a one-sample compiling pass."""
    import taichi as ti

    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    start = time.perf_counter()
    renderer = Renderer(scene, job.size)
    camera = CameraFrame.from_spec(scene.camera)
    renderer.render(camera, 1, job.integrator, seed=job.seed)
    ti.sync()
    compiled = time.perf_counter()
    renderer.render(camera, job.spp - 1, job.integrator, seed=job.seed)
    ti.sync()
    end = time.perf_counter()
    pixels = job.size[0] * job.size[1]
    return {"name": "1 process x all cores", "wall_s": end - start,
            "samples_per_s": (job.spp - 1) * pixels / (end - compiled), "image": renderer.image(),
            "state": renderer.state()}


def distributed(scene, job, workers: int, chunk_spp: int | None) -> dict:
    from renderer.commands.distributed.render import DistributedOptions, DistributedRun, render_distributed

    run = DistributedRun()
    start = time.perf_counter()
    result = render_distributed(scene, job, DistributedOptions(workers=workers, threads=1, chunk_spp=chunk_spp), run=run)
    wall = time.perf_counter() - start
    steady = [(trip - render, render) for trip, render in zip(run.chunk_round_trips, run.chunk_seconds)]
    steady = steady[workers:]  # each worker's first chunk compiles: its time says nothing of a chunk's cost
    overhead = statistics.median(o for o, _ in steady) if steady else float("nan")
    render_median = statistics.median(r for _, r in steady) if steady else float("nan")
    return {"name": f"{workers} worker{'s' if workers > 1 else ''} x 1 thread"
                    + (f", {chunk_spp}-spp chunks" if chunk_spp else ""),
            "workers": workers, "chunk_spp": chunk_spp, "wall_s": wall,
            "samples_per_s": sum(s.rate for s in run.worker_stats.values()), "groups": run.groups,
            "chunks": run.chunks, "bytes_per_chunk": run.bytes_moved / max(1, run.chunks),
            "scene_bytes": run.scene_bytes, "chunk_overhead_ms": 1e3 * overhead,
            "chunk_render_ms": 1e3 * render_median, "overhead_fraction": overhead / render_median if steady else None,
            "image": result.image, "state": result.state}


def run(quick: bool = False, out_dir: Path = Path("reports"), config: ScaleBenchConfig | None = None) -> int:
    from renderer.runtime.arch import init_taichi
    from renderer.commands.distributed.cluster import RayCluster
    from renderer.commands.headless import RenderJob

    config = config or (QUICK if quick else FULL)
    out_dir = Path(out_dir)
    load_before = load_average()
    import taichi as ti

    if not ti.lang.impl.get_runtime().prog:
        init_taichi("cpu", optimize="compile")
    scene = load_named_scene(config.scene)
    job = RenderJob(spp=config.spp, size=config.size, integrator=config.integrator, seed=config.seed)
    log(f"{config.scene} {config.size[0]}x{config.size[1]}, {config.spp} spp, {config.integrator}: one process")
    rows = [one_process(scene, job)]
    with RayCluster(cpus=2, address=None):
        for workers, chunk_spp in config.distributed_runs:
            log(f"{workers} workers, chunks of {chunk_spp or 'about 2 s'}")
            rows.append(distributed(scene, job, workers, chunk_spp))
    base = rows[0]
    for row in rows:
        row["speed_up"] = row["samples_per_s"] / base["samples_per_s"]
        row["efficiency_per_thread"] = row["speed_up"] * (2 / row.get("workers", 2))
        row["bit_identical"] = all(np.array_equal(getattr(row["state"], name), getattr(base["state"], name))
                                   for name in ("mean", "m2", "count", "rejected"))
    overheads = [r["chunk_overhead_ms"] for r in rows[1:] if r["chunk_overhead_ms"] == r["chunk_overhead_ms"]]
    worst = max(overheads) if overheads else float("nan")
    rule_s = worst / 1e3 / OVERHEAD_TARGET
    report = {**report_header("scale", quick, load_before, scene=config.scene, size=list(config.size),
                              spp=config.spp, integrator=config.integrator),
              "runs": [{k: v for k, v in r.items() if k not in ("image", "state")} for r in rows],
              "chunk_rule": {"overhead_ms": worst, "overhead_target": OVERHEAD_TARGET,
                             "min_chunk_render_s": rule_s,
                             "text": (f"a chunk renders at least {rule_s:.2f} s ({1 / OVERHEAD_TARGET:.0f}x the largest "
                                      f"median overhead measured, {worst:.1f} ms) for its overhead to stay under "
                                      f"{100 * OVERHEAD_TARGET:.0f}%; the default rule aims at 2 s")}}
    print_table(["run", "Msamples/s", "speed-up", "efficiency/thread", "wall s", "chunks", "KB/chunk",
                 "overhead ms", "render ms", "overhead", "bit-identical"],
                [[r["name"], r["samples_per_s"] / 1e6, r["speed_up"], r["efficiency_per_thread"], r["wall_s"],
                  r.get("chunks", "-"), r["bytes_per_chunk"] / 1e3 if "bytes_per_chunk" in r else "-",
                  r.get("chunk_overhead_ms", "-"), r.get("chunk_render_ms", "-"),
                  f"{100 * r['overhead_fraction']:.1f}%" if r.get("overhead_fraction") is not None else "-",
                  "yes" if r["bit_identical"] else "NO"] for r in rows],
                title=f"bench scale: {config.scene} {config.size[0]}x{config.size[1]} {config.spp} spp {config.integrator}")
    print(report["chunk_rule"]["text"])
    out_dir.mkdir(parents=True, exist_ok=True)
    write_json(out_dir / "bench_scale.json", report)
    plot(report, out_dir / "bench_scale.png")
    return 0 if all(r["bit_identical"] for r in rows) else 1


def plot(report: dict, path: Path) -> Path:
    plt = pyplot()
    runs = report["runs"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 3.6))
    left.barh([r["name"] for r in runs], [r["samples_per_s"] / 1e6 for r in runs], color="tab:blue")
    left.set_xlabel("Msamples/s after compiling")
    left.invert_yaxis()
    chunked = [r for r in runs if r.get("chunk_render_ms")]
    right.scatter([r["chunk_render_ms"] for r in chunked], [100 * (r["overhead_fraction"] or 0) for r in chunked])
    for r in chunked:
        right.annotate(r["name"], (r["chunk_render_ms"], 100 * (r["overhead_fraction"] or 0)), fontsize=7)
    right.axhline(100 * OVERHEAD_TARGET, color="grey", linestyle="--")
    right.set_xscale("log")
    right.set_xlabel("median chunk render time (ms)")
    right.set_ylabel("overhead (% of render time)")
    fig.suptitle(f"bench scale: {report['scene']} {report['size'][0]}x{report['size'][1]}, {report['spp']} spp")
    return save_figure(fig, path)

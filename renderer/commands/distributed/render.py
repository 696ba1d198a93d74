"""The driver of a distributed still render: chunks to Ray workers, their pixels merged into one film.

The merged film is exact: each chunk returns its pixels' new (mean, m2, count, rejected) and AOV
state, computed sample by sample in the same order as one process would, so the image is
bit-identical to a one-process render with the same seed and spp (same back-end and optimisation
level), whatever the number of workers, the chunks' sizes and the order they return in. A chunk
lost with its worker is handed to another worker from the same state: the result is unchanged.
"""
from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from renderer.commands.distributed.cluster import RayCluster, WorkerPool, WorkerStats
from renderer.commands.distributed.planner import MAX_SPP, Chunk, ChunkPlanner, ChunkSizer
from renderer.film.accumulation import FilmState
from renderer.commands.headless import RenderJob, RenderResult, Resume
from renderer.film.pixel_slices import ROUND_SLICES, filled_mean_array
from renderer.scene.description import Scene

WAIT_SECONDS = 0.25  # the driver wakes at least this often for progress, stop requests and checkpoints
# Pixel state the driver may send and receive per second, all workers together: a share of a 1 Gbit/s
# link that leaves room for the object store's own traffic (docs/distributed.md).
DRIVER_BYTES_PER_SECOND = 50e6


@dataclass(frozen=True)
class DistributedOptions:
    workers: int | None = None  # None on a cluster: its CPUs over the threads of a worker
    address: str | None = None  # None: a local Ray started for the run
    threads: int | None = None  # CPU threads per worker
    chunk_spp: int | None = None  # None: ChunkSizer's rule
    chunk_seconds: float = 2.0

    def threads_per_worker(self) -> int:
        if self.threads:
            return self.threads
        return local_threads(self.workers or 1) if self.address is None else 1

    def cluster(self) -> RayCluster:
        """The Ray to run on: a local instance with a CPU per worker thread, or the cluster joined."""
        return RayCluster(None if self.address else (self.workers or 1) * self.threads_per_worker(), self.address)

    def worker_count(self, ray) -> int:
        """The workers asked for, or as many as the cluster's CPUs hold."""
        return self.workers or max(1, int(ray.cluster_resources().get("CPU", 1)) // self.threads_per_worker())

    def where(self, arch: str) -> str:
        """Where the render runs, in words."""
        place = f"the Ray cluster at {self.address}" if self.address else "a local Ray instance"
        count = f"{self.workers} workers" if self.workers else "its workers"
        return f"{count} ({arch}) on {place}"


@dataclass
class DistributedRun:
    """What happened besides the image: for the command's report, the tests and `bench scale`."""

    workers: int = 0
    groups: int = 0
    chunks: int = 0
    lost_chunks: int = 0  # chunks re-run because their worker died
    bytes_moved: int = 0  # pixel state sent to and received from workers
    scene_bytes: int = 0
    worker_stats: dict[int, WorkerStats] = field(default_factory=dict)
    chunk_seconds: list[float] = field(default_factory=list)  # rendering time of each chunk
    chunk_round_trips: list[float] = field(default_factory=list)  # submit to merged, each chunk


class MergedFilm:
    """The driver's film: the merged state, what checkpoints save (a FilmSource)."""

    def __init__(self, state: FilmState):
        self.merged = state

    def state(self) -> FilmState:
        return self.merged


def local_threads(workers: int) -> int:
    return max(1, (os.cpu_count() or 1) // workers)


def render_distributed(scene: Scene, job: RenderJob, options: DistributedOptions, arch: str = "cpu",
                       optimize: str = "compile", load_options=None, progress=None, stop=None, checkpoints=None,
                       resume: Resume | None = None, run: DistributedRun | None = None,
                       on_worker_started=None) -> RenderResult:
    """Render `job` on Ray workers. Taichi must be initialised in this process (on the CPU: the
    driver runs adaptive sampling's checks and the final statistics on its own film).
    `on_worker_started(chunk, pid)`: called as each chunk is handed out (tests kill workers there)."""
    from renderer.commands.distributed.bundle import SceneBundle
    from renderer.commands.distributed.cluster import worker_actor
    from renderer.commands.distributed.pixel_groups import PixelSlices, empty_state, group_count
    from renderer.commands.distributed.worker import WorkerSettings
    from renderer.integrators import make_integrator

    job = job.resolved(scene)
    if hasattr(make_integrator(job.integrator), "make_program"):
        raise ValueError(f"{job.integrator} renders whole-image photon passes and cannot be distributed; use path, "
                         "nee or mis")
    width, height = job.size
    adaptive = job.noise_threshold is not None
    # The adaptive layer is kept even for uniform sampling, as a one-process film keeps it.
    state = _starting_state(resume, width, height, True, job.keeps_aovs, empty_state)
    slices = PixelSlices(width, height)
    run = run if run is not None else DistributedRun()
    threads = options.threads_per_worker()
    start = time.perf_counter()
    with options.cluster() as ray:
        workers = options.worker_count(ray)
        groups = group_count(width * height, workers)
        planner = ChunkPlanner(slices.progress(state), groups, job.spp, job.min_spp if adaptive else None)
        bundle = SceneBundle.of(scene)
        settings = WorkerSettings((width, height), job.integrator, job.max_depth, job.seed, arch, optimize, threads,
                                  job.keeps_aovs, load_options)
        run.workers, run.groups, run.scene_bytes = workers, groups, bundle.size
        actor_class = worker_actor(ray, threads, gpu=arch == "cuda")
        bundle_ref = ray.put(bundle)
        round_trip = 2 * sum(a.nbytes for a in slices.gather(state, 0, planner.size).values())
        seconds = chunk_seconds(options.chunk_seconds, workers, round_trip)
        driver = _Driver(ray, actor_class, bundle_ref, settings, planner, slices, state, job, run, stop,
                         ChunkSizer(options.chunk_spp, seconds), on_worker_started)
        driver.start(workers)
        seconds_before = resume.seconds_rendered if resume is not None else 0.0
        driver.loop(seconds_before, progress, checkpoints)
    film = driver.film()
    variance = film.variance_of_mean_image()
    samples = state.count + state.rejected
    return RenderResult(filled_mean_array(state.mean, samples), planner.samples_done(), time.perf_counter() - start,
                        int(state.rejected.sum()), job.integrator, variance, driver.interrupted,
                        driver.rendered(), film, _slices_in_round(planner), state,
                        driver.pixels_active if adaptive else None, MergedFilm(state))


def chunk_seconds(target: float, workers: int, round_trip_bytes: int) -> float:
    """How long a chunk should render: `target`, or longer where the workers together would send the
    driver more than DRIVER_BYTES_PER_SECOND of pixel state (many workers, large images)."""
    return max(target, workers * round_trip_bytes / DRIVER_BYTES_PER_SECOND)


def _starting_state(resume, width, height, adaptive, aovs, empty_state) -> FilmState:
    if resume is None:
        return empty_state(width, height, adaptive, aovs)
    state = resume.state
    if adaptive and state.adaptive is None:
        state.adaptive = np.zeros_like(state.count)
    if aovs and (state.albedo is None or state.normal is None):  # as Renderer.restore: AOVs start over
        state.albedo = np.zeros_like(state.mean)
        state.normal = np.zeros_like(state.mean)
        state.aov_count = np.zeros_like(state.count)
    elif aovs:
        state.aov_count = state.aov_samples()
    return state


def _slices_in_round(planner: ChunkPlanner) -> int:
    """Slices of the next sample already rendered (a render stopped with groups at different counts)."""
    return int(round((planner.mean_spp() - planner.samples_done()) * ROUND_SLICES))


class _Driver:
    """The loop: hand out chunks to idle workers, merge what returns, replace workers that die."""

    def __init__(self, ray, actor_class, bundle_ref, settings, planner: ChunkPlanner, slices, state: FilmState,
                 job: RenderJob, run: DistributedRun, stop, sizer: ChunkSizer, on_worker_started):
        self.ray, self.actor_class, self.bundle_ref, self.settings = ray, actor_class, bundle_ref, settings
        self.planner, self.slices, self.state, self.job, self.run = planner, slices, state, job, run
        self.stop, self.sizer, self.on_worker_started = stop, sizer, on_worker_started
        self.pool = WorkerPool(ray, actor_class, bundle_ref, settings, run)
        self.idle = self.pool.idle
        self.pending: dict = {}  # object ref -> (actor, chunk, submitted at)
        self.compiled: set = set()  # actors past their first chunk
        self.interrupted = False
        self.budget_start: float | None = None
        self.seconds_before = 0.0
        self.pixels_active = state.count.size
        self._film = None
        self._adaptive_rule = None

    def film(self):
        """The driver's Taichi film, holding the merged state (adaptive checks, final statistics)."""
        from renderer.film.accumulation import Film

        if self._film is None:
            self._film = Film(*self.state.size)
        self._film.restore(self.state)
        return self._film

    def start(self, workers: int) -> None:
        self.pool.spawn(workers)

    # --- the loop ------------------------------------------------------------------------------------
    def rendered(self) -> float:
        running = time.perf_counter() - self.budget_start if self.budget_start is not None else 0.0
        return self.seconds_before + running

    def loop(self, seconds_before: float, progress, checkpoints) -> None:
        self.seconds_before = seconds_before
        planner, job = self.planner, self.job
        while True:
            if self.stop is not None and self.stop.requested and not planner.stopped:
                planner.stop()
                self.interrupted = True
            if (job.seconds is not None and planner.target is None and self.budget_start is not None
                    and self.rendered() >= job.seconds):
                planner.end_soon()
            if planner.at_barrier():
                self._check_adaptive()
                continue
            if planner.finished():
                break
            self._hand_out()
            ready, _ = self.ray.wait(list(self.pending), num_returns=1, timeout=WAIT_SECONDS)
            for ref in ready:
                self._collect(ref)
            if self.budget_start is not None:
                if progress is not None:
                    progress(planner.mean_spp(), job.spp, self.rendered(), self.run.worker_stats, job.seconds)
                if checkpoints is not None:
                    checkpoints.after_pass(MergedFilm(self.state), planner.samples_done(), self.rendered(),
                                           self._expected_seconds(), _slices_in_round(planner))

    def _hand_out(self) -> None:
        planner, job = self.planner, self.job
        while self.idle:
            actor = self.idle[0]
            seconds_left = (job.seconds - self.rendered() if job.seconds is not None and self.budget_start is not None
                            and planner.target is None else None)
            spp = self.sizer.spp(planner.size, actor not in self.compiled, seconds_left)
            chunk = planner.next_chunk(min(spp, MAX_SPP))
            if chunk is None:
                return
            self.idle.pop(0)
            submitted = time.perf_counter()
            arrays = self.slices.gather(self.state, chunk.first, chunk.count)
            self.run.bytes_moved += sum(a.nbytes for a in arrays.values())
            ref = actor.render_chunk.remote(chunk, arrays)
            self.pending[ref] = (actor, chunk, submitted)
            if self.on_worker_started is not None:
                self.on_worker_started(chunk, self.pool.pids[actor])

    def _collect(self, ref) -> None:
        actor, chunk, submitted = self.pending.pop(ref)
        try:
            arrays, seconds = self.ray.get(ref)
        except self.ray.exceptions.RayActorError:
            self._lost(actor, chunk)
            return
        except self.ray.exceptions.RayTaskError as error:
            raise self.pool.failure(actor, error) from None
        self.slices.scatter(self.state, chunk.first, chunk.count, arrays)
        self.run.bytes_moved += sum(a.nbytes for a in arrays.values())
        first = actor not in self.compiled
        self.planner.complete(chunk)
        self.sizer.record(chunk, seconds, first)
        stats = self.run.worker_stats[self.pool.ids[actor]]
        stats.chunks += 1
        if not first:
            stats.samples += chunk.spp * self.slices.pixels(chunk.first, chunk.count)
            stats.seconds += seconds
        self.run.chunks += 1
        self.run.chunk_seconds.append(seconds)
        self.run.chunk_round_trips.append(time.perf_counter() - submitted)
        self.compiled.add(actor)
        self.idle.append(actor)
        if self.budget_start is None:
            self.budget_start = time.perf_counter()  # a --time budget counts from the first chunk back

    def _lost(self, actor, chunk: Chunk) -> None:
        """`actor` died with `chunk`: the chunk goes back to the planner, a new worker takes its place."""
        self.planner.abandon(chunk)
        self.pool.replace(actor, f"a chunk of slices {chunk.first}-{chunk.first + chunk.count - 1} at {chunk.start} spp")

    def _check_adaptive(self) -> None:
        """Adaptive sampling's check on the merged film: the one a single process runs at this point."""
        from renderer.film.adaptive import AdaptiveSampling

        film = self.film()
        if self._adaptive_rule is None:
            self._adaptive_rule = AdaptiveSampling(film)
        self.pixels_active = self._adaptive_rule.check(self.job.noise_threshold, self.job.min_spp)
        self.state.adaptive[...] = film.state().adaptive
        self.planner.passed_barrier(self.slices.progress(self.state))

    def _expected_seconds(self) -> float:
        if self.job.seconds is not None:
            return self.job.seconds
        rate = sum(s.rate for s in self.run.worker_stats.values())
        left = (self.job.spp - self.planner.mean_spp()) * self.state.count.size
        return self.rendered() + (left / rate if rate > 0 else 0.0)


def progress_line(stream=sys.stderr):
    """A progress bar over every worker: spp of the image, samples/s of each worker and in total."""
    from renderer.commands.headless import progress_head

    def report(spp, target, elapsed, workers: dict[int, WorkerStats], seconds):
        head, eta = progress_head(spp, target, elapsed, seconds)
        rates = " ".join(f"w{n} {s.rate / 1e6:.2f}" for n, s in sorted(workers.items()))
        total = sum(s.rate for s in workers.values()) / 1e6
        stream.write(f"\r{head}  {total:6.2f} Msamples/s ({rates})  ETA {eta:5.1f} s ")
        stream.flush()

    return report

"""Starting or joining Ray for a render, and the render's actors.

Ray is imported here only, when a distributed render asks for it: Lantern works without it. A
local instance started for a run is shut down after it; a cluster joined (--ray-address) or a Ray
the caller already started is left running.
"""
from __future__ import annotations

import logging
import os
import socket
import sys
from dataclasses import dataclass
from pathlib import Path

PACKAGE_ROOT = Path(__file__).resolve().parents[3]  # the folder holding the `renderer` package
SHIPPED_PACKAGES = ("renderer", "shaders_sdf")  # what a remote node needs of this checkout to render
ADDRESS_TIMEOUT = 5.0  # seconds to wait for a cluster's address to answer


def import_ray():
    try:
        import ray
    except ImportError:
        raise RuntimeError("distributed rendering needs Ray, which is not installed (pip install ray)") from None
    return ray


def check_address(address: str) -> None:
    """A one-line error unless something listens at a host:port (or ray://host:port) address; Ray's
    own connect would retry for minutes."""
    if address == "auto":
        return
    target = address.split("://", 1)[-1]
    host, _, port = target.rpartition(":")
    if not host or not port.isdigit():
        raise RuntimeError(f"--ray-address {address}: expected host:port, ray://host:port or auto")
    try:
        socket.create_connection((host, int(port)), timeout=ADDRESS_TIMEOUT).close()
    except OSError as error:
        raise RuntimeError(f"--ray-address {address}: no Ray cluster answers there ({error.strerror or error})") from None


class RayCluster:
    """`with RayCluster(cpus, address) as ray:` the Ray module, initialised for the run."""

    def __init__(self, cpus: int | None, address: str | None):
        self.cpus = cpus
        self.address = address
        self._started = False

    def __enter__(self):
        ray = import_ray()
        if self.address is not None:
            check_address(self.address)
        if ray.is_initialized():
            return ray  # a Ray the caller started (a test, a notebook): used as it is
        quiet = {"include_dashboard": False, "log_to_driver": False, "logging_level": logging.ERROR,
                 "configure_logging": True}
        if self.address is not None:
            # The nodes get this Lantern's code; its dependencies (taichi, numpy...) must be installed there.
            try:
                ray.init(address=self.address, runtime_env={"py_modules": [str(PACKAGE_ROOT / name) for name in SHIPPED_PACKAGES]}, **quiet)
            except Exception as error:  # noqa: BLE001 - Ray raises ConnectionError, RuntimeError, ValueError...
                first = (str(error).strip().splitlines() or [type(error).__name__])[0]
                raise RuntimeError(f"--ray-address {self.address}: could not join the Ray cluster ({first}); a "
                                   "cluster with token authentication also needs RAY_AUTH_MODE=token here") from None
        else:
            # Workers import the same Lantern as this process, whichever checkout it runs from.
            path = os.pathsep.join(p for p in (str(PACKAGE_ROOT), os.environ.get("PYTHONPATH")) if p)
            ray.init(num_cpus=self.cpus, runtime_env={"env_vars": {"PYTHONPATH": path}}, **quiet)
        self._started = True
        return ray

    def __exit__(self, *exc) -> None:
        if self._started:
            import ray

            ray.shutdown()


def worker_actor(ray, threads: int | None, gpu: bool):
    """The RenderWorker class as a Ray actor needing `threads` CPUs (and a GPU for --arch cuda)."""
    from renderer.commands.distributed.worker import RenderWorker

    return ray.remote(RenderWorker).options(num_cpus=threads or 1, num_gpus=1 if gpu else 0, max_restarts=0)


@dataclass
class WorkerStats:
    """What a worker has done: for the progress line and the benchmark."""

    host: str = ""
    samples: int = 0  # pixel samples
    seconds: float = 0.0  # rendering, excluding its first (compiling) chunk
    chunks: int = 0

    @property
    def rate(self) -> float:
        return self.samples / self.seconds if self.seconds > 0 else 0.0


# Workers that die this many times per worker of the render end it: something kills them all.
MAX_LOSSES_PER_WORKER = 3


class WorkerPool:
    """The render's actors: started, numbered, their process ids known, replaced when they die.
    `run` (render.DistributedRun) gets a WorkerStats per worker and counts the losses."""

    def __init__(self, ray, actor_class, bundle_ref, settings, run):
        self.ray, self.actor_class, self.bundle_ref, self.settings, self.run = ray, actor_class, bundle_ref, settings, run
        self.idle: list = []  # actors waiting for work
        self.ids: dict = {}  # actor -> worker number (1, 2, ...)
        self.pids: dict = {}  # actor -> its process id

    def spawn(self, count: int = 1) -> None:
        """Start `count` workers (in parallel) and wait until each has its scene; one-line errors."""
        actors = [self.actor_class.remote(self.bundle_ref, self.settings) for _ in range(count)]
        for actor, hello in zip(actors, self.ray.get([a.hello.remote() for a in actors])):
            if hello["error"]:
                raise RuntimeError(f"worker on {hello['host']}: {hello['error']}")
            number = len(self.ids) + 1
            self.ids[actor], self.pids[actor] = number, hello["pid"]
            self.run.worker_stats[number] = WorkerStats(host=hello["host"])
            self.idle.append(actor)

    def failure(self, actor, error) -> RuntimeError:
        """A worker's task that raised (Ray's RayTaskError), as one line naming the worker."""
        cause = getattr(error, "cause", None)
        return RuntimeError(f"worker {self.ids[actor]}: {cause or str(error).splitlines()[0]}")

    def replace(self, actor, what: str) -> None:
        """`actor` died doing `what`: say so, start another in its place."""
        self.run.lost_chunks += 1
        if self.run.lost_chunks > MAX_LOSSES_PER_WORKER * max(1, self.run.workers):
            raise RuntimeError(f"{self.run.lost_chunks} chunks lost with their workers: giving up")
        print(f"\nworker {self.ids[actor]} died during {what}: re-running it on a new worker", file=sys.stderr)
        self.spawn()

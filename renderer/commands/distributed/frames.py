"""Animation frames as Ray tasks: each worker renders whole frames on its own compiled Renderer.

The same contract as renderer/commands/animation/frames.LocalFrames (results in the order of the requests;
a stop request hands out no further frame), with frames handed to idle workers as they free up,
and a frame lost with its worker rendered again by a new one. A frame rendered on a worker is the
still render of its camera, as in one process (same back-end and optimisation level).
"""
from __future__ import annotations

from typing import Iterator, Sequence

from renderer.commands.animation.frames import FrameRequest, FrameResult
from renderer.commands.headless import RenderJob
from renderer.scene.description import Scene


class RayFrames:
    def __init__(self, scene: Scene, job: RenderJob, args):
        from renderer.commands.distributed.render import DistributedOptions

        self.scene = scene
        self.job = job.resolved(scene)
        self.options = DistributedOptions(getattr(args, "workers", None), getattr(args, "ray_address", None),
                                          getattr(args, "worker_threads", None))
        self.arch = getattr(args, "arch", None) or "cpu"
        self.optimize = getattr(args, "optimize", None) or "compile"
        self.run = None  # the DistributedRun of the last render() (tests, reports)

    def render(self, requests: Sequence[FrameRequest], stop=None) -> Iterator[FrameResult]:
        from renderer.commands.distributed.bundle import SceneBundle
        from renderer.commands.distributed.cluster import WorkerPool, worker_actor
        from renderer.commands.distributed.render import DistributedRun
        from renderer.commands.distributed.worker import WorkerSettings

        options, job = self.options, self.job
        threads = options.threads_per_worker()
        self.run = run = DistributedRun()
        with options.cluster() as ray:
            workers = max(1, min(options.worker_count(ray), len(requests)))
            settings = WorkerSettings(job.size, job.integrator, job.max_depth, job.seed, self.arch, self.optimize,
                                      threads, job.keeps_aovs, self.scene.model_files.options)
            bundle = SceneBundle.of(self.scene)
            run.workers, run.scene_bytes = workers, bundle.size
            pool = WorkerPool(ray, worker_actor(ray, threads, gpu=self.arch == "cuda"), ray.put(bundle), settings, run)
            pool.spawn(workers)
            waiting = list(requests)
            pending: dict = {}  # object ref -> (actor, request)
            done: dict[int, FrameResult] = {}
            order = [request.index for request in requests]
            while waiting or pending:
                if stop is not None and stop.requested:
                    waiting.clear()
                while waiting and pool.idle:
                    actor, request = pool.idle.pop(0), waiting.pop(0)
                    pending[actor.render_frame.remote(request, job)] = (actor, request)
                if not pending:
                    break
                ready, _ = ray.wait(list(pending), num_returns=1)
                actor, request = pending.pop(ready[0])
                try:
                    done[request.index] = ray.get(ready[0])
                except ray.exceptions.RayActorError:
                    waiting.insert(0, request)
                    pool.replace(actor, f"frame {request.index}")
                    continue
                except ray.exceptions.RayTaskError as error:
                    raise pool.failure(actor, error) from None
                run.chunks += 1
                pool.idle.append(actor)
                while order and order[0] in done:  # in the order of the requests
                    yield done.pop(order.pop(0))
            while order and order[0] in done:
                yield done.pop(order.pop(0))

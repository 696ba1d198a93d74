"""The worker of a distributed render: one Ray actor, one Taichi runtime, one compiled Renderer.

Plain Python (no Ray import): cluster.py wraps it as an actor. Errors while starting (a scene that
does not load on that node, an arch the node lacks) are kept and reported by hello(), so the driver
can say them in one line instead of a dead actor's traceback.
"""
from __future__ import annotations

import os
import socket
import time
from dataclasses import dataclass

import numpy as np

from renderer.commands.distributed.bundle import SceneBundle
from renderer.commands.distributed.planner import Chunk
from renderer.scene.load_options import LoadOptions


@dataclass(frozen=True)
class WorkerSettings:
    size: tuple[int, int]
    integrator: str
    max_depth: int
    seed: int
    arch: str = "cpu"
    optimize: str = "compile"
    threads: int | None = None  # CPU threads (None: every core of the node)
    aovs: bool = False
    load_options: LoadOptions | None = None


class RenderWorker:
    def __init__(self, bundle: SceneBundle, settings: WorkerSettings):
        self.settings = settings
        self.error: str | None = None
        self.arch = None
        try:
            self._start(bundle, settings)
        except Exception as error:  # noqa: BLE001 - any start-up failure is reported by hello()
            self.error = f"{type(error).__name__}: {error}" if not str(error) else str(error)

    def _start(self, bundle: SceneBundle, settings: WorkerSettings) -> None:
        from renderer.runtime.arch import init_taichi
        from renderer.camera import CameraFrame
        from renderer.commands.distributed.pixel_groups import PixelSlices
        from renderer.renderer import Renderer
        from renderer.scene.catalog import load_any

        self.arch = init_taichi(settings.arch, optimize=settings.optimize, cpu_threads=settings.threads)
        scene = load_any(bundle.scene_path(), settings.load_options)
        self.scene = scene
        self.renderer = Renderer(scene, settings.size, aovs=settings.aovs)
        self.camera = CameraFrame.from_spec(scene.camera)
        self.slices = PixelSlices(*settings.size)

    def hello(self) -> dict:
        """Who and where this worker is, and why it cannot work if it cannot."""
        return {"pid": os.getpid(), "host": socket.gethostname(), "arch": self.arch, "error": self.error}

    def render_frame(self, request, job):
        """A whole animation frame (renderer/commands/animation/frames.py): the still render of the job with
        the request's camera, denoised where the job asks."""
        from renderer.commands.animation.frames import FrameResult
        from renderer.commands.headless import render

        if self.error is not None:
            raise RuntimeError(self.error)
        result = render(self.scene, job, renderer=self.renderer, camera=request.camera)
        image = result.image
        if job.denoise:
            from renderer.output.denoise import Denoiser
            from renderer.output.render_outputs import denoised

            self._denoiser = getattr(self, "_denoiser", None) or Denoiser()
            image = denoised(result, self._denoiser)
        return FrameResult(request.index, image, result.spp, result.seconds, result.rejected, result.interrupted)

    def render_chunk(self, chunk: Chunk, arrays: dict[str, np.ndarray]) -> tuple[dict[str, np.ndarray], float]:
        """Render `chunk` from its pixels' state `arrays` (PixelSlices.gather); their new state and
        the seconds the rendering took (compilation included on a worker's first chunk)."""
        import taichi as ti

        if self.error is not None:
            raise RuntimeError(self.error)
        xs, ys = self.slices.coords(chunk.first, chunk.count)
        renderer, settings = self.renderer, self.settings
        film_arrays = dict(arrays)
        film_arrays.setdefault("adaptive", np.zeros(len(xs), np.int32))
        renderer.film.write_pixels(xs, ys, film_arrays)
        if renderer.aovs is not None:
            renderer.aovs.write_pixels(xs, ys, arrays["albedo"], arrays["normal"], arrays["aov_count"])
        start = time.perf_counter()
        renderer.render_pass(self.camera, chunk.spp, chunk.first, chunk.count, settings.integrator,
                             settings.max_depth, settings.seed)
        ti.sync()
        seconds = time.perf_counter() - start
        out = {name: value for name, value in renderer.film.read_pixels(xs, ys).items() if name in arrays}
        if renderer.aovs is not None and "albedo" in arrays:
            out["albedo"], out["normal"], out["aov_count"] = renderer.aovs.read_pixels(xs, ys)
        return out, seconds

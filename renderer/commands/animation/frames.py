"""The frame loop behind a small interface, so that frames can be rendered elsewhere.

run_animation (command.py) hands a list of FrameRequests to any object with
`render(requests, stop) -> Iterator[FrameResult]` and writes each result it gets. LocalFrames
renders them here, one after another, on one Renderer: the kernels compile once and each frame
only clears the film and changes the camera. Each frame is a still render of the job (its spp
or --time budget, seed, integrator, adaptive sampling, denoising), so a frame equals the still
render of the scene with that frame's camera, bit for bit.

The contract of `render(requests, stop)`, for any implementation: results come in the order of
the requests; `stop` is a StopRequests (renderer/commands/interrupts.py) whose request ends the frame in
progress early (its result then says `interrupted`) and renders no further frame; a frame
stopped before its first sample yields nothing.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator, Protocol, Sequence

import numpy as np

from renderer.camera import CameraFrame
from renderer.commands.headless import RenderJob
from renderer.scene.description import Scene


@dataclass
class FrameRequest:
    index: int  # the frame number (its file's number)
    time: float  # seconds: index / fps
    camera: CameraFrame


@dataclass
class FrameResult:
    index: int
    image: np.ndarray  # linear (H, W, 3) float32, denoised where the job asks: the image to write
    spp: int  # samples every pixel has
    seconds: float  # wall time of the frame (the first one's includes compiling)
    rejected: int  # non-finite samples dropped
    interrupted: bool  # stopped by a request before its budget was spent


class FrameRenderer(Protocol):
    def render(self, requests: Sequence[FrameRequest], stop) -> Iterator[FrameResult]: ...


class LocalFrames:
    """Frames rendered in this process (Taichi initialised by the caller)."""

    def __init__(self, scene: Scene, job: RenderJob):
        self.scene = scene
        self.job = job.resolved(scene)

    def render(self, requests: Sequence[FrameRequest], stop=None) -> Iterator[FrameResult]:
        from renderer.commands.headless import render
        from renderer.renderer import Renderer

        job = self.job
        renderer = Renderer(self.scene, job.size, aovs=job.keeps_aovs)
        denoiser = None
        if job.denoise:
            from renderer.output.denoise import Denoiser

            denoiser = Denoiser()
        for request in requests:
            result = render(self.scene, job, stop=stop, renderer=renderer, camera=request.camera)
            if result.mean_spp == 0:  # stopped before its first pass
                return
            image = result.image
            if denoiser is not None:
                from renderer.output.render_outputs import denoised

                image = denoised(result, denoiser)
            yield FrameResult(request.index, image, result.spp, result.seconds, result.rejected,
                              result.interrupted)
            if result.interrupted:
                return

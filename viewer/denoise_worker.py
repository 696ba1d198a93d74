"""The viewer's denoiser: Open Image Denoise on a worker thread, so input is never blocked.

The window loop offers the accumulated image whenever the camera is still; the worker takes it
when idle and when the accumulation has doubled its samples since the last result (1, 2, 4 ...
spp: each doubling halves the noise a denoised image starts from, and a denoise of a 960x540
frame costs ~0.4-3 s on this CPU, so denoising every frame would fall behind). The first job of
an accumulation may use a quicker denoiser (`first`: the viewer's skips prefiltering the AOVs,
~0.4 s instead of ~2.7 s at 960x540), so a clean image comes within a second of stopping and the
better one follows. The result is
shown only while it belongs to the accumulation on screen: any change of scene, integrator,
camera or setting makes a new accumulation `generation`, and an older result is dropped.
The OIDN call releases the GIL (a C call through cffi): rendering continues meanwhile.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from renderer.output.denoise import DenoiseInput


@dataclass(frozen=True)
class Denoised:
    generation: int
    spp: float  # the accumulation's mean spp when it was taken
    image: np.ndarray  # linear (H, W, 3)
    seconds: float  # the denoiser's time
    quick: bool = False  # made by the quicker first denoiser


def wants_denoise(spp: float, last_spp: Optional[float]) -> bool:
    """Denoise at the first whole sample per pixel, then each time the samples double."""
    if spp < 1.0:
        return False
    return last_spp is None or spp >= 2.0 * last_spp


class BackgroundDenoiser:
    """One worker thread, one job at a time; the newest result is kept."""

    def __init__(self, denoise: Callable[[DenoiseInput], np.ndarray],
                 first: Optional[Callable[[DenoiseInput], np.ndarray]] = None):
        self._denoise = denoise
        self._first = first  # for the first job of each generation, when given
        self._lock = threading.Lock()
        self._result: Optional[Denoised] = None
        self._busy = False
        self._thread: Optional[threading.Thread] = None
        self._last_job: Optional[tuple] = None  # (generation, spp) of the last job started
        self.error: Optional[str] = None  # a failure, one line (the view falls back to the raw image)

    @property
    def busy(self) -> bool:
        return self._busy

    def offer(self, generation: int, spp: float, take_input: Callable[[], DenoiseInput]) -> bool:
        """Start a job if idle and the accumulation has doubled since the last job of this
        generation; `take_input` is called only then (downloading the film costs a few ms)."""
        last_spp = self._last_job[1] if self._last_job and self._last_job[0] == generation else None
        if self._busy or not wants_denoise(spp, last_spp):
            return False
        source = take_input()
        self._busy = True
        self._last_job = (generation, spp)
        quick = last_spp is None and self._first is not None
        self._thread = threading.Thread(target=self._work, args=(generation, spp, source, quick), daemon=True,
                                        name="lantern-denoise")
        self._thread.start()
        return True

    def _work(self, generation: int, spp: float, source: DenoiseInput, quick: bool) -> None:
        start = time.perf_counter()
        try:
            image = (self._first if quick else self._denoise)(source)
            with self._lock:
                self._result = Denoised(generation, spp, image, time.perf_counter() - start, quick)
                self.error = None
        except Exception as error:  # noqa: BLE001 - a failed denoise must not end the viewer
            self.error = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        finally:
            self._busy = False

    def result_for(self, generation: int) -> Optional[Denoised]:
        """The newest result if it belongs to `generation`, else None."""
        with self._lock:
            result = self._result
        return result if result is not None and result.generation == generation else None

    def wait(self, timeout: float = 10.0) -> None:
        """Block until the running job ends (screenshots, tests)."""
        thread = self._thread
        if thread is not None:
            thread.join(timeout)

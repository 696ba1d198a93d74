"""Denoising with Intel Open Image Denoise (the `pyoidn` package, prebuilt OIDN 2.x).

The renderer's image is HDR linear radiance; OIDN's "RT" filter takes it with the albedo and
normal AOVs of renderer/aovs.py (cleaner inputs than the colour: `clean_aux` is left off, as they
are Monte Carlo estimates too, only far less noisy). Non-finite values never reach the library:
the film drops non-finite samples, and the inputs are checked again here, since one NaN would
spread over the filter's whole receptive field.

The call releases the GIL (a C call through cffi), so the viewer runs it in a worker thread.
"""
from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np


def unavailable_reason() -> str | None:
    """Why denoising cannot run here (one line), or None when it can."""
    try:
        import pyoidn  # noqa: F401
    except ImportError as error:
        return (f"denoising needs the pyoidn package (Intel Open Image Denoise), which is not installed "
                f"or has no build for this platform ({error})")
    except OSError as error:  # the shared library failed to load
        return f"denoising: Intel Open Image Denoise failed to load ({error})"
    return None


@dataclass(frozen=True)
class DenoiseInput:
    """What the denoiser is given: linear colour, and the AOVs when the integrator wrote them."""

    color: np.ndarray  # float32 (H, W, 3)
    albedo: np.ndarray | None = None
    normal: np.ndarray | None = None


def sanitized(image: np.ndarray, low: float, high: float) -> np.ndarray:
    """float32, C-contiguous, non-finite values replaced by 0 and the rest clipped to [low, high]."""
    out = np.nan_to_num(np.asarray(image, dtype=np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    return np.ascontiguousarray(np.clip(out, low, high))


class Denoiser:
    """OIDN's RT filter, one call at a time (pyoidn keeps its device and filter per process, so
    only the first call pays for creating them)."""

    def __init__(self, quality: str = "high"):
        reason = unavailable_reason()
        if reason:
            raise RuntimeError(reason)
        import pyoidn

        self._oidn = pyoidn
        self.quality = quality
        self._lock = threading.Lock()

    def denoise(self, source: DenoiseInput) -> np.ndarray:
        """The denoised colour, float32 (H, W, 3), non-negative."""
        color = sanitized(source.color, 0.0, np.finfo(np.float32).max)
        albedo = normal = None
        if source.albedo is not None and source.normal is not None:
            albedo = sanitized(source.albedo, 0.0, 1.0)
            normal = sanitized(source.normal, -1.0, 1.0)
        with self._lock:
            out = self._oidn.denoise(color, albedo, normal, hdr=True, quality=self.quality)
        return np.maximum(np.asarray(out, dtype=np.float32).reshape(color.shape), 0.0)

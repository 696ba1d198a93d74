"""Denoising with Intel Open Image Denoise (the `pyoidn` package, prebuilt OIDN 2.x).

The renderer's image is HDR linear radiance; OIDN's "RT" filter takes it with the albedo and
normal AOVs of renderer/film/aovs.py. Those AOVs are Monte Carlo estimates too (anti-aliased edges,
depth of field, textures under a pixel's footprint), so by default they are first denoised on
their own and the colour filter is told they are clean (`cleanAux`), as OIDN's documentation
recommends for the best quality. Measured against long references (mis, relMSE less the
reference's noise) with the noisy AOVs passed straight in: at 320x180 and 8 spp, cornell_box
0.00117 -> 0.00092, studio 0.00571 -> 0.00533, textured 0.00778 -> 0.00556, showcase 0.00521 ->
0.00473, bunnies 0.00853 -> 0.00982 (better on four of five); at 160x90 from 8 to 512 spp on
cornell_box, studio and textured, better at 9 of 12 points and 4-7% worse at the other three
(cornell_box at 8 and 32 spp, textured at 128). It costs about three filter passes instead of
one (`bench denoise`, 960x540 on two cores: 0.43 s without, 2.8 s with), so the viewer asks for
the quick form first (`prefilter_aux=False`).

Non-finite values never reach the library: the film drops non-finite samples, and the inputs are
checked again here, since one NaN would spread over the filter's whole receptive field.

The calls release the GIL (C calls through cffi), so the viewer runs them in a worker thread.
"""
from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np

QUALITIES = ("high", "balanced", "fast")


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


class OidnFilters:
    """One OIDN CPU device and one RT filter per role (colour, albedo, normal), made on first use.

    A filter's images are bound for one call and unbound after it, so no filter keeps a pointer
    to an array Python may free."""

    def __init__(self):
        import pyoidn

        self._oidn = pyoidn
        self._device = pyoidn.Device()
        self._device.commit()
        self._check("device creation")
        self._filters = {}

    def _check(self, operation: str) -> None:
        message = self._device.get_error()
        if message:
            raise RuntimeError(f"Open Image Denoise: {operation} failed: {message}")

    def run(self, role: str, images: dict[str, np.ndarray], quality: str, **flags: bool) -> np.ndarray:
        """Filter `images` (OIDN image names -> float32 (H, W, 3)); returns the output image."""
        oidn = self._oidn
        flt = self._filters.get(role)
        if flt is None:
            flt = self._filters[role] = oidn.Filter(self._device, oidn.OIDN_FILTER_TYPE_RT)
            self._check("filter creation")
        output = np.zeros_like(next(iter(images.values())))
        bound = dict(images, output=output)
        try:
            for name, image in bound.items():
                flt.set_image(name, image, oidn.OIDN_FORMAT_FLOAT3)
            for name, value in flags.items():
                flt.set_bool(name, value)
            flt.set_quality(getattr(oidn, f"OIDN_QUALITY_{quality.upper()}"))
            flt.commit()
            self._check(f"{role} filter commit")
            flt.execute()
            self._check(f"{role} filter")
        finally:
            for name in bound:
                flt.unset_image(name)
        return output


class Denoiser:
    """OIDN's RT filter on colour (+ albedo + normal), one call at a time; the device and filters
    are made once per Denoiser, so only its first call pays for creating them."""

    def __init__(self, quality: str = "high", prefilter_aux: bool = True):
        reason = unavailable_reason()
        if reason:
            raise RuntimeError(reason)
        if quality not in QUALITIES:
            raise ValueError(f"denoise quality must be one of {', '.join(QUALITIES)}, not {quality!r}")
        self.quality = quality
        self.prefilter_aux = prefilter_aux
        self._filters: OidnFilters | None = None
        self._lock = threading.Lock()

    def denoise(self, source: DenoiseInput, prefilter_aux: bool | None = None) -> np.ndarray:
        """The denoised colour, float32 (H, W, 3), non-negative. `prefilter_aux` overrides the
        Denoiser's own setting for this call."""
        prefilter = self.prefilter_aux if prefilter_aux is None else prefilter_aux
        images = {"color": sanitized(source.color, 0.0, np.finfo(np.float32).max)}
        if source.albedo is not None and source.normal is not None:
            images["albedo"] = sanitized(source.albedo, 0.0, 1.0)
            images["normal"] = sanitized(source.normal, -1.0, 1.0)
        else:
            prefilter = False
        with self._lock:
            if self._filters is None:
                self._filters = OidnFilters()
            run = self._filters.run
            if prefilter:
                # (sanitized again: whatever the prefilters return, the colour filter sees finite AOVs)
                images["albedo"] = sanitized(run("albedo", {"albedo": images["albedo"]}, self.quality), 0.0, 1.0)
                images["normal"] = sanitized(run("normal", {"normal": images["normal"]}, self.quality), -1.0, 1.0)
            out = run("color", images, self.quality, hdr=True, cleanAux=prefilter)
        return np.maximum(out.reshape(images["color"].shape), 0.0)

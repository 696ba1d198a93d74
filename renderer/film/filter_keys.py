"""The pixel filters by name, and each as the key kernels compile it in (renderer/film/pixel_filter.py
samples them). Plain Python: the scene format's schema reads the names without Taichi."""
from __future__ import annotations

import math

PIXEL_FILTERS = ("box", "tent", "gaussian")
GAUSSIAN_RADIUS_STDDEVS = 4.0  # Mitsuba cuts its Gaussian off at four standard deviations


def filter_key(kind: str, stddev: float = 0.5, radius: float = 1.0) -> tuple:
    """The filter as a kernel compiles it in (part of Features): ("box",), ("tent", radius, tails) or
    ("gaussian", stddev, cut-off radius, bias, tails). `tails[d]`: the share
    of the filter's integral beyond d + 1/2 pixels on one side, for the pixels d from an image edge
    (the filter is cut at the edges and renormalised there, as Mitsuba's film does)."""
    if kind == "box":
        return ("box",)
    if kind == "tent":
        r = float(radius)
        tails = tuple((r - a) ** 2 / (2.0 * r * r) if a < r else 0.0 for a in _edge_distances(r))
        return ("tent", r, tails)
    if kind == "gaussian":
        s = float(stddev)
        r = GAUSSIAN_RADIUS_STDDEVS * s
        bias = math.exp(-r * r / (2.0 * s * s))

        def integral(a: float, b: float) -> float:  # of the windowed Gaussian over [a, b], 0 <= a <= b <= r
            return (s * math.sqrt(math.pi / 2.0) * (math.erf(b / (s * math.sqrt(2.0))) - math.erf(a / (s * math.sqrt(2.0))))
                    - bias * (b - a))

        whole = 2.0 * integral(0.0, r)
        tails = tuple(integral(a, r) / whole if a < r else 0.0 for a in _edge_distances(r))
        return ("gaussian", s, r, bias, tails)
    raise ValueError(f"unknown pixel filter '{kind}' (choose from {', '.join(PIXEL_FILTERS)})")


def _edge_distances(radius: float) -> list[float]:
    """Where the image's edge is from a pixel's centre, for the pixels the filter reaches past it."""
    return [d + 0.5 for d in range(math.ceil(radius - 0.5))] or [0.5]

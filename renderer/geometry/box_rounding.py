"""Boxes stored in f32 that still contain what they bound: f64 corners are rounded outwards (lo
towards -inf, hi towards +inf); f32 corners are used exactly. The BVH build and the light tree
both keep their boxes this way."""
import numpy as np


def _to_f32(x, toward, overshoots) -> np.ndarray:
    """x in f32, rounded towards `toward` where rounding to nearest went the other way."""
    if x.dtype == np.float32:
        return np.ascontiguousarray(x)
    x64 = x.astype(np.float64)
    with np.errstate(over="ignore"):
        y = x64.astype(np.float32)
    bad = overshoots(y.astype(np.float64), x64)
    if bad.any():
        y[bad] = np.nextafter(y[bad], np.float32(toward))
    return y


def round_out_f32(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) as f32 arrays with lo32 <= lo and hi32 >= hi element by element."""
    lo, hi = np.asarray(lo), np.asarray(hi)
    return _to_f32(lo, -np.inf, np.greater), _to_f32(hi, np.inf, np.less)

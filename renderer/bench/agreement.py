"""Whether two renders of one scene agree in expectation, judged as Mitsuba's render tests judge it:
each pixel channel's z-test of the difference of the means against their combined standard error
at a Sidak-corrected level (the whole image at `alpha`), at least PASS_FRACTION of them passing;
and the image means, far more sensitive to a small bias spread over the whole image. Images come
as (mean, variance of the mean) per pixel and channel. `compare` and the test suite use this one
rule."""
from __future__ import annotations

import numpy as np

ALPHA = 0.01
PASS_FRACTION = 0.9975  # Mitsuba's rule: at least 99.75 % of the pixel channels pass


def pixel_z_scores(mean_a, var_a, mean_b, var_b) -> np.ndarray:
    """|difference| / combined standard error per pixel channel (inf where neither image has noise
    and they differ, 0 where they are equal)."""
    ma, va, mb, vb = (np.asarray(x, np.float64) for x in (mean_a, var_a, mean_b, var_b))
    difference = np.abs(ma - mb)
    combined = va + vb
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(combined == 0.0, np.where(difference == 0.0, 0.0, np.inf), difference / np.sqrt(combined))


def pixel_z_test(mean_a, var_a, mean_b, var_b, alpha: float = ALPHA):
    """(passed, fraction of pixel channels passing, pass mask, p-values, Sidak level)."""
    from scipy import stats

    z = pixel_z_scores(mean_a, var_a, mean_b, var_b)
    pixels = z.shape[0] * z.shape[1]
    p_value = 2.0 * stats.norm.sf(z)  # 1 where equal without noise, 0 where they differ without it
    level = -np.expm1(np.log1p(-alpha) / pixels)  # 1 - (1 - alpha)^(1/N) without cancellation
    success = p_value > level
    fraction = np.count_nonzero(success) / 3 / pixels
    return fraction >= PASS_FRACTION, fraction, success, p_value, level


def image_mean_z(a, b, channel: int = 1) -> float:
    """z of the difference of two images' means in one channel (pixels independent)."""
    (ma, va), (mb, vb) = a, b
    n = ma[..., channel].size
    d = float(np.mean(ma[..., channel], dtype=np.float64) - np.mean(mb[..., channel], dtype=np.float64))
    se = float(np.sqrt((np.sum(va[..., channel], dtype=np.float64) + np.sum(vb[..., channel], dtype=np.float64)) / n**2))
    return d / se if se > 0 else (0.0 if d == 0 else float("inf"))

"""Statistical comparisons of rendered images, as Mitsuba's render tests make them.

Images come as (mean, variance of the mean) pairs per pixel and channel. The per-pixel rule:
each pixel's z-test of the difference of the means against their combined standard error, at a
Sidak-corrected level so the whole image is tested at `alpha`; at least PASS_FRACTION of the pixel
channels must pass. The image mean adds a test far more sensitive to a small bias spread over
the whole image than any single pixel.
"""
import numpy as np
from scipy import stats

# The rule itself lives with the product (compare uses it too); the suite reads it from there.
from renderer.bench.agreement import ALPHA, PASS_FRACTION, image_mean_z, pixel_z_test  # noqa: E402,F401


def describe(a, b, p_value, names) -> str:
    """The worst pixels and the image means of two (mean, var) pairs, for a failure message."""
    (ma, va), (mb, vb) = a, b
    lines = [f"image means: {names[0]} {ma.mean(axis=(0, 1))}, {names[1]} {mb.mean(axis=(0, 1))}",
             "worst pixels (row, col): a vs b (sd a, sd b), p"]
    w = ma.shape[1]
    for index in np.argsort(p_value.min(axis=2), axis=None)[:6]:
        r, c = divmod(int(index), w)
        lines.append(f"  ({r}, {c}) {np.round(ma[r, c], 4)} vs {np.round(mb[r, c], 4)} "
                     f"({np.round(np.sqrt(va[r, c]), 4)}, {np.round(np.sqrt(vb[r, c]), 4)}), p = {p_value[r, c].min():.1e}")
    return "\n".join(lines)


def mean_z(mean, var_of_mean, expected, channel=1):
    """z of the image mean of one channel against `expected` (pixels independent)."""
    m = np.asarray(mean, np.float64)[..., channel]
    v = np.asarray(var_of_mean, np.float64)[..., channel]
    return (m.mean() - expected) / np.sqrt(v.sum() / m.size ** 2)


def assert_agree(a, b, names, alpha=ALPHA):
    """The per-pixel rule, then the image means (one channel, green)."""
    passed, fraction, _, p_value, level = pixel_z_test(*a, *b, alpha=alpha)
    assert passed, (f"{names[0]} vs {names[1]}: {fraction:.2%} of the pixels pass at the Sidak level {level:.1e} "
                    f"(need {PASS_FRACTION:.2%})\n" + describe(a, b, p_value, names))
    z = image_mean_z(a, b)
    critical = stats.norm.isf(alpha / 2)
    assert abs(z) < critical, (f"{names[0]} vs {names[1]}: image means (green) differ, z = {z:.2f} "
                               f"(critical {critical:.2f})\n" + describe(a, b, p_value, names))

"""CIE 1931 2-degree colour matching functions (an analytic fit) and the conversions from
spectra to linear Rec.709 RGB.

Colour matching functions
    The multi-lobe piecewise-Gaussian fit of Wyman, Sloan and Shirley 2013 ("Simple Analytic
    Approximations to the CIE XYZ Color Matching Functions", JCGT 2(2), their multi-lobe fit):
    each lobe is w exp(-(lambda - mu)^2 / (2 sigma^2)) with sigma = sigma_lo below mu and
    sigma_hi above. Against the CIE 1931 table at 5 nm (tests/data/cie1931_2deg_5nm.csv) its
    largest absolute error is 0.015 (x-bar), 0.0071 (y-bar) and 0.024 (z-bar, whose peak is
    1.78); RMS errors 0.0061, 0.0029, 0.0047. Its integrals over [360, 830] nm are
    106.766, 106.922 and 106.875 nm against the table's 106.858, 106.857 and 106.858: within 0.1 %.
    (The test measures these numbers.)

XYZ -> linear Rec.709
    `XYZ_TO_REC709` is derived here from the Rec.709 primaries and the D65 white point (x, y
    chromaticities of ITU-R BT.709), so RGB (1, 1, 1) is D65 at Y = 1.

Spectra -> linear Rec.709 (the renderer's radiance space)
    The renderer's white, RGB (1, 1, 1), must be the constant spectrum 1 (illuminant E), so that a
    white furnace renders white with spectral transport as it does with RGB transport. Hence
    `SPECTRUM_TO_REC709` = XYZ_TO_REC709 . Bradford(E -> D65) / Y_integral, where "E" is the XYZ
    of the constant spectrum *under this fit* and Y_integral is the fit's own integral of y-bar:
    the constant spectrum 1 maps to RGB (1, 1, 1) to rounding, whatever the fit's small errors.
    `spectral_rgb_weights(lambda)` = SPECTRUM_TO_REC709 . cmf(lambda) is the RGB one unit of
    spectral radiance at lambda contributes per nm: a spectral sample f(lambda) drawn with pdf
    p(lambda) adds f(lambda) * spectral_rgb_weights(lambda) / p(lambda) to the pixel.
"""
from __future__ import annotations

import math

import numpy as np
import taichi as ti

from renderer.spectral.wavelengths import LAMBDA_MAX, LAMBDA_MIN

vec3 = ti.math.vec3

# (channel 0/1/2 = x/y/z, weight, mu nm, sigma below mu nm, sigma above mu nm): Wyman et al. 2013.
CMF_LOBES = (
    (0, 1.056, 599.8, 37.9, 31.0),
    (0, 0.362, 442.0, 16.0, 26.7),
    (0, -0.065, 501.1, 20.4, 26.2),
    (1, 0.821, 568.8, 46.9, 40.5),
    (1, 0.286, 530.9, 16.3, 31.1),
    (2, 1.217, 437.0, 11.8, 36.0),
    (2, 0.681, 459.0, 26.0, 13.8),
)

# Chromaticities (x, y) of ITU-R BT.709 / sRGB primaries and of D65.
REC709_PRIMARIES = ((0.64, 0.33), (0.30, 0.60), (0.15, 0.06))
D65_WHITE = (0.3127, 0.3290)
# Bradford cone-response matrix (Lam 1985), the usual choice for von Kries adaptation.
BRADFORD = np.array([[0.8951, 0.2664, -0.1614],
                     [-0.7502, 1.7135, 0.0367],
                     [0.0389, -0.0685, 1.0296]])


def _xyz_of(xy) -> np.ndarray:
    x, y = xy
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


def _rgb_to_xyz(primaries, white) -> np.ndarray:
    """The RGB -> XYZ matrix whose columns are the primaries scaled so RGB (1,1,1) = white (Y = 1)."""
    p = np.stack([_xyz_of(c) for c in primaries], axis=1)
    return p * np.linalg.solve(p, _xyz_of(white))[None, :]


def _lobe_integral(w, mu, s_lo, s_hi, a, b) -> float:
    """Integral of one piecewise-Gaussian lobe over [a, b] (closed form with erf)."""
    def part(sigma, lo, hi):
        if hi <= lo:
            return 0.0
        k = sigma * math.sqrt(0.5 * math.pi)
        return k * (math.erf((hi - mu) / (sigma * math.sqrt(2.0))) - math.erf((lo - mu) / (sigma * math.sqrt(2.0))))
    return w * (part(s_lo, a, min(b, mu)) + part(s_hi, max(a, mu), b))


def cmf_integrals(a: float = LAMBDA_MIN, b: float = LAMBDA_MAX) -> np.ndarray:
    """(integral of x-bar, y-bar, z-bar) of the fit over [a, b] nm."""
    out = np.zeros(3)
    for ch, w, mu, s_lo, s_hi in CMF_LOBES:
        out[ch] += _lobe_integral(w, mu, s_lo, s_hi, a, b)
    return out


CMF_INTEGRALS = cmf_integrals()
Y_INTEGRAL = float(CMF_INTEGRALS[1])
REC709_TO_XYZ = _rgb_to_xyz(REC709_PRIMARIES, D65_WHITE)
XYZ_TO_REC709 = np.linalg.inv(REC709_TO_XYZ)


def bradford(src_white_xyz, dst_white_xyz) -> np.ndarray:
    """The Bradford adaptation matrix taking XYZ seen under `src` white to `dst` white."""
    lms_src = BRADFORD @ np.asarray(src_white_xyz, np.float64)
    lms_dst = BRADFORD @ np.asarray(dst_white_xyz, np.float64)
    return np.linalg.inv(BRADFORD) @ np.diag(lms_dst / lms_src) @ BRADFORD


SPECTRUM_TO_REC709 = XYZ_TO_REC709 @ bradford(CMF_INTEGRALS / Y_INTEGRAL, _xyz_of(D65_WHITE)) / Y_INTEGRAL

_XYZ_TO_REC709_ROWS = tuple(tuple(float(v) for v in row) for row in XYZ_TO_REC709)
_SPECTRUM_TO_REC709_ROWS = tuple(tuple(float(v) for v in row) for row in SPECTRUM_TO_REC709)


# --- Taichi ----------------------------------------------------------------------------------


@ti.func
def cmf_xyz(lam):
    """(x-bar, y-bar, z-bar) at wavelength lam (nm), the Wyman et al. 2013 fit."""
    xyz = vec3(0.0)
    for i in ti.static(range(len(CMF_LOBES))):
        ch, w, mu, s_lo, s_hi = ti.static(CMF_LOBES[i])
        sigma = s_lo if lam < mu else s_hi
        t = (lam - mu) / sigma
        xyz[ch] += w * ti.exp(-0.5 * t * t)
    return xyz


@ti.func
def xyz_to_rec709(xyz):
    return ti.Matrix(_XYZ_TO_REC709_ROWS, ti.f32) @ xyz


@ti.func
def spectral_rgb_weights(lam):
    """Linear Rec.709 RGB per unit spectral radiance at lam, per nm (see the module doc)."""
    return ti.Matrix(_SPECTRUM_TO_REC709_ROWS, ti.f32) @ cmf_xyz(lam)


# --- numpy -----------------------------------------------------------------------------------


def cmf_xyz_np(lam) -> np.ndarray:
    """(..., 3) colour matching functions (the fit) at wavelengths lam (...), float64."""
    lam = np.asarray(lam, np.float64)
    out = np.zeros(lam.shape + (3,))
    for ch, w, mu, s_lo, s_hi in CMF_LOBES:
        sigma = np.where(lam < mu, s_lo, s_hi)
        out[..., ch] += w * np.exp(-0.5 * ((lam - mu) / sigma) ** 2)
    return out


def xyz_to_rec709_np(xyz) -> np.ndarray:
    return np.asarray(xyz, np.float64) @ XYZ_TO_REC709.T


def spectral_rgb_weights_np(lam) -> np.ndarray:
    return cmf_xyz_np(lam) @ SPECTRUM_TO_REC709.T

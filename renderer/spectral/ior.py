"""Index of refraction as a function of wavelength: Cauchy and Sellmeier models with presets.

Both take the wavelength in nanometres and use micrometres inside, the unit the published
coefficients are given in.

Cauchy (two terms)
    n(lambda) = A + B / lambda^2, lambda in um, B in um^2. Cheap; good over the visible for
    glasses, poor near absorption bands.
Sellmeier (up to four terms)
    n(lambda)^2 = 1 + sum_i B_i lambda^2 / (lambda^2 - C_i), lambda in um, C_i in um^2. The form
    glass catalogues publish. Coefficients are vec4 (B1..B4, C1..C4); three-term glasses leave the
    fourth at B4 = C4 = 0, which adds 0 (the term's numerator is 0, its denominator lambda^2 > 0).
    Valid where lambda^2 stays clear of every C_i, which holds over 360-830 nm for the presets
    (their resonances lie below 0.17 um and above 3 um). n^2 is clamped at 1 so a misuse far from
    that range cannot yield NaN.

Presets (physical constants, from the cited measurements):
    bk7           Schott N-BK7 data sheet (Schott optical glass catalogue): n_d = 1.5168, V_d = 64.17.
    fused_silica  Malitson 1965, J. Opt. Soc. Am. 55, 1205 (C_i are the squares of his
                  resonance wavelengths 0.0684043, 0.1162414, 9.896161 um): n_d = 1.4585, V_d = 67.8.
    sf11          Schott SF11 dense flint data sheet: n_d = 1.7847, V_d = 25.68.
    water         Daimon and Masumura 2007, Appl. Opt. 46, 3811 (distilled water at 20 C, their
                  four-term fit): n_d = 1.3334, V_d = 55.76.
Cauchy presets: two-term least-squares fits to each Sellmeier preset over 400-700 nm, computed
at import. For BK7 the fit is A = 1.5046, B = 0.00420 um^2, the textbook values; the fits stay
within 2e-4 of their Sellmeier curves over 400-700 nm, except SF11's (3.4e-3: a dense flint
disperses too strongly for two terms).
"""
from __future__ import annotations

import numpy as np
import taichi as ti

vec4 = ti.math.vec4

# name: ((B1, B2, B3, B4), (C1, C2, C3, C4 in um^2))
SELLMEIER_PRESETS = {
    "bk7": ((1.03961212, 0.231792344, 1.01046945, 0.0),
            (0.00600069867, 0.0200179144, 103.560653, 0.0)),
    "fused_silica": ((0.6961663, 0.4079426, 0.8974794, 0.0),
                     (0.0684043 ** 2, 0.1162414 ** 2, 9.896161 ** 2, 0.0)),
    "sf11": ((1.73759695, 0.313747346, 1.89878101, 0.0),
             (0.013188707, 0.0623068142, 155.23629, 0.0)),
    "water": ((5.684027565e-1, 1.726177391e-1, 2.086189578e-2, 1.130748688e-1),
              (5.101829712e-3, 1.821153936e-2, 2.620722293e-2, 1.069792721e1)),
}

CAUCHY_FIT_RANGE = (400.0, 700.0)  # nm

# Fraunhofer lines used for n_d and the Abbe number V_d = (n_d - 1) / (n_F - n_C), nm.
LINE_D = 587.5618  # helium d
LINE_F = 486.1327  # hydrogen F
LINE_C = 656.2725  # hydrogen C


@ti.func
def cauchy_ior(lam_nm, a, b):
    l_um = lam_nm * 1e-3
    return a + b / (l_um * l_um)


@ti.func
def sellmeier_ior(lam_nm, b, c):
    """b, c: vec4 coefficients (c in um^2); lam_nm in nm."""
    l2 = (lam_nm * 1e-3) ** 2
    n2 = 1.0
    for i in ti.static(range(4)):
        n2 += b[i] * l2 / (l2 - c[i])
    return ti.sqrt(ti.max(n2, 1.0))


def sellmeier_ior_np(lam_nm, b, c) -> np.ndarray:
    l2 = (np.asarray(lam_nm, np.float64) * 1e-3) ** 2
    n2 = 1.0 + sum(bi * l2 / (l2 - ci) for bi, ci in zip(b, c))
    return np.sqrt(np.maximum(n2, 1.0))


def cauchy_ior_np(lam_nm, a, b) -> np.ndarray:
    l_um = np.asarray(lam_nm, np.float64) * 1e-3
    return a + b / (l_um * l_um)


def preset_ior_np(name: str, lam_nm) -> np.ndarray:
    """n(lambda) of a Sellmeier preset."""
    b, c = SELLMEIER_PRESETS[name]
    return sellmeier_ior_np(lam_nm, b, c)


def fit_cauchy(lam_nm, n) -> tuple[float, float]:
    """(A, B um^2): the least-squares Cauchy fit to indices n at wavelengths lam_nm."""
    inv_l2 = 1.0 / (np.asarray(lam_nm, np.float64) * 1e-3) ** 2
    design = np.stack([np.ones_like(inv_l2), inv_l2], axis=1)
    a, b = np.linalg.lstsq(design, np.asarray(n, np.float64), rcond=None)[0]
    return float(a), float(b)


def _cauchy_presets() -> dict:
    lam = np.linspace(*CAUCHY_FIT_RANGE, 301)
    return {name: fit_cauchy(lam, preset_ior_np(name, lam)) for name in SELLMEIER_PRESETS}


# name: (A, B in um^2), fitted to the Sellmeier presets (see the module doc)
CAUCHY_PRESETS = _cauchy_presets()


def abbe_number(ior) -> float:
    """V_d = (n_d - 1) / (n_F - n_C) of `ior(lam_nm) -> n` (a callable)."""
    n_d, n_f, n_c = (float(ior(x)) for x in (LINE_D, LINE_F, LINE_C))
    return (n_d - 1.0) / (n_f - n_c)

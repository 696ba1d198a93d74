"""A spectrum given as (wavelength, value) samples made into linear Rec.709 RGB the way Mitsuba 3's
RGB variants do it when they read a scene (src/core/spectrum.cpp, `spectrum_list_to_srgb`), so a
Mitsuba scene's colours are the colours Mitsuba renders.

The rule:
    * 1000 wavelengths w_i = 360 + 470 i / 999 nm; those outside the spectrum's first and last
      sample add nothing (a spectrum that stops at 590 nm has no red);
    * the spectrum is linear between its samples; the CIE 1931 colour matching functions and
      illuminant D65 are linear between their 5 nm rows (data/cie1931_d65_5nm.csv, as float32);
    * XYZ = sum cmf(w_i) value(w_i) [d65(w_i) / 98.997...] * 470 / 1000 / 106.750..., the two
      normalisations making a unit spectrum (and a unit reflectance under D65) luminance 1;
    * RGB = Mitsuba's XYZ -> linear sRGB matrix; negative channels become 0 and, where the spectrum is
      a reflectance (`bounded`), channels above 1 become 1.
Mitsuba integrates reflectances against D65 (so a constant reflectance of 1 is RGB white) and
emission spectra without it (bounded=False, d65=False); a spectrum read from a file (a conductor's
eta and k) is unbounded and without D65 too.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

TABLE_FILE = Path(__file__).resolve().parent / "data" / "cie1931_d65_5nm.csv"
CIE_MIN, CIE_MAX, CIE_SAMPLES = 360.0, 830.0, 95
STEPS = 1000
Y_NORMALIZATION = 1.0 / 106.7502593994140625  # a unit spectrum integrates to luminance 1
D65_NORMALIZATION = 1.0 / 98.99741751876255  # D65 integrates to luminance 1
XYZ_TO_SRGB = np.array([[3.240479, -1.537150, -0.498535],
                        [-0.969256, 1.875991, 0.041556],
                        [0.055648, -0.204043, 1.057311]], np.float32).astype(np.float64)


@lru_cache(maxsize=1)
def tables() -> tuple[np.ndarray, np.ndarray]:
    """((95, 3) x-bar, y-bar, z-bar; (95,) D65) at 360, 365, ..., 830 nm, as float32 (Mitsuba's
    precision) widened to float64. Read once per process: the file never changes."""
    lines = [line for line in TABLE_FILE.read_text().splitlines() if line and not line.startswith("#")]
    data = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])  # after the header
    grid = CIE_MIN + 5.0 * np.arange(CIE_SAMPLES)
    if data.shape != (CIE_SAMPLES, 5) or not np.array_equal(data[:, 0], grid):
        raise ValueError(f"{TABLE_FILE}: expected the 5 nm rows from 360 to 830 nm")
    cmf = data[:, 1:4].astype(np.float32).astype(np.float64)
    d65 = data[:, 4].astype(np.float32).astype(np.float64)
    return cmf, d65


def _table_at(table: np.ndarray, w: np.ndarray) -> np.ndarray:
    """A 5 nm table read linearly at wavelengths w inside [360, 830] (Mitsuba's cie1931_xyz)."""
    t = (w - CIE_MIN) * ((CIE_SAMPLES - 1) / (CIE_MAX - CIE_MIN))
    i0 = np.clip(t.astype(np.int64), 0, CIE_SAMPLES - 2)
    w1 = t - i0
    if table.ndim == 2:
        w1 = w1[:, None]
    return (1.0 - w1) * table[i0] + w1 * table[i0 + 1]


def spectrum_to_rgb(wavelengths, values, bounded: bool = True, d65: bool = False) -> tuple[float, float, float]:
    """Linear Rec.709 RGB of a sampled spectrum (wavelengths in nm, increasing), Mitsuba's way."""
    wavelengths = np.asarray(wavelengths, np.float64)
    values = np.asarray(values, np.float64)
    if wavelengths.ndim != 1 or wavelengths.shape != values.shape or len(wavelengths) < 2:
        raise ValueError("a spectrum needs at least two (wavelength, value) pairs")
    if np.any(np.diff(wavelengths) <= 0):
        raise ValueError("a spectrum's wavelengths must increase")
    cmf, d65_table = tables()
    w = CIE_MIN + (np.arange(STEPS) / (STEPS - 1)) * (CIE_MAX - CIE_MIN)
    w = w[(w >= wavelengths[0]) & (w <= wavelengths[-1])]
    index = np.clip(np.searchsorted(wavelengths, w, side="right") - 1, 0, len(wavelengths) - 2)
    w0, w1 = wavelengths[index], wavelengths[index + 1]
    v = ((w - w1) * values[index] + (w0 - w) * values[index + 1]) / (w0 - w1)
    if d65:
        v = v * _table_at(d65_table, w) * D65_NORMALIZATION
    xyz = (_table_at(cmf, w) * v[:, None]).sum(axis=0) * (CIE_MAX - CIE_MIN) * Y_NORMALIZATION / STEPS
    rgb = np.maximum(XYZ_TO_SRGB @ xyz, 0.0)
    if bounded:
        rgb = np.minimum(rgb, 1.0)
    return tuple(float(c) for c in rgb.astype(np.float32))

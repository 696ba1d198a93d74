"""Spectra made RGB as Mitsuba 3's RGB variants make them (renderer/spectral/mitsuba_rgb.py): its
normalisations (a unit emission spectrum has luminance 1, a unit reflectance under D65 is white),
its clamps, and the shipped CIE and D65 tables."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.spectral.mitsuba_rgb import CIE_SAMPLES, spectrum_to_rgb, tables

REC709_Y = np.array([0.212671, 0.715160, 0.072169])  # Mitsuba's luminance weights


def test_tables_are_the_cie_rows():
    cmf, d65 = tables()
    assert cmf.shape == (CIE_SAMPLES, 3) and d65.shape == (CIE_SAMPLES,)
    # Spot values of the CIE 1931 observer and of D65 (100 at 560 nm by definition).
    assert cmf[(555 - 360) // 5, 1] == pytest.approx(1.0)
    assert cmf[(600 - 360) // 5, 0] == pytest.approx(1.0622, rel=1e-6)
    assert d65[(560 - 360) // 5] == pytest.approx(100.0)
    # Riemann sums at 5 nm: the y-bar integral is the CIE's 106.86 nm, D65 x y-bar Mitsuba's 98.997 x 106.75.
    assert cmf[:, 1].sum() * 5 == pytest.approx(106.86, rel=1e-3)
    assert (cmf[:, 1] * d65).sum() * 5 == pytest.approx(98.99741751876255 * 106.7502593994140625, rel=2e-3)


def test_a_unit_emission_spectrum_has_luminance_one():
    rgb = np.array(spectrum_to_rgb([360, 830], [1, 1], bounded=False, d65=False))
    assert REC709_Y @ rgb == pytest.approx(1.0, rel=2e-3)
    assert rgb[0] > rgb[2]  # the equal-energy white is reddish against D65 white


def test_a_unit_reflectance_under_d65_is_white():
    np.testing.assert_allclose(spectrum_to_rgb([360, 830], [1, 1], bounded=True, d65=True), (1, 1, 1), rtol=2e-3)


def test_reflectances_are_clamped_to_one_and_nothing_is_negative():
    assert max(spectrum_to_rgb([360, 830], [3, 3], bounded=True, d65=True)) == 1.0
    assert max(spectrum_to_rgb([360, 830], [3, 3], bounded=False, d65=True)) > 2.9
    monochrome = spectrum_to_rgb([519, 520, 521], [0, 10, 0], bounded=False)  # out of the sRGB gamut
    assert min(monochrome) == 0.0 and monochrome[1] > 0


def test_wavelengths_outside_the_spectrum_add_nothing():
    red_cut = spectrum_to_rgb([360, 590], [1, 1], bounded=False)
    zero_beyond = spectrum_to_rgb([360, 590, 590.01, 830], [1, 1, 0, 0], bounded=False)
    np.testing.assert_allclose(red_cut, zero_beyond, rtol=1e-3)
    assert red_cut[0] < 0.5 * spectrum_to_rgb([360, 830], [1, 1], bounded=False)[0]


def test_linearity():
    a = np.array(spectrum_to_rgb([400, 550, 700], [0.1, 0.5, 0.2], bounded=False))
    b = np.array(spectrum_to_rgb([400, 550, 700], [0.2, 1.0, 0.4], bounded=False))
    np.testing.assert_allclose(b, 2 * a, rtol=1e-6)


@pytest.mark.parametrize("wavelengths, values", [([500], [1]), ([500, 400], [1, 2]), ([400, 500], [1])])
def test_bad_spectra(wavelengths, values):
    with pytest.raises(ValueError):
        spectrum_to_rgb(wavelengths, values)

"""Dispersive dielectrics (renderer/materials/dispersion.py, spectral paths in the tracer).

- The index of refraction per wavelength equals the published curves (Sellmeier presets against
  an independent numpy evaluation; Cauchy from ior and Abbe number hits n_d and V).
- A prism of apex 60 degrees deviates each wavelength by the angle Snell's law gives, with the
  renderer's own refraction (lobes.dielectric_sample) at both faces.
- With a constant index (Abbe number 1e9), the spectral path tracer agrees with the RGB one on a
  grey scene by Mitsuba's per-pixel rule and by the image mean (alpha 0.01, Sidak over pixels).
- Only scenes with dispersive materials compile spectral code.
"""
import math

import numpy as np
import pytest
import taichi as ti

from renderer.camera import CameraFrame
from renderer.materials import dispersion, lobes
from renderer.materials.table import MaterialTable
from renderer.renderer import Renderer
from renderer.scene.features import scene_features
from renderer.scene.description import MaterialSpec
from renderer.spectral.ior import LINE_C, LINE_D, LINE_F, SELLMEIER_PRESETS
from tests.stats.image_tests import assert_agree
from tests.scene_builder import scene_from_toml

WAVELENGTHS = np.array([400.0, 450.0, 486.1327, 550.0, 587.5618, 656.2725, 700.0], np.float32)


@ti.kernel
def _ior_kernel(table: ti.template(), row: ti.i32, lams: ti.types.ndarray(dtype=ti.f32, ndim=1),
                out: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(lams.shape[0]):
        out[i] = dispersion.ior_at(table.table[row], lams[i])


@ti.kernel
def _prism_kernel(table: ti.template(), row: ti.i32, lams: ti.types.ndarray(dtype=ti.f32, ndim=1),
                  incidence: ti.f32, apex: ti.f32, out: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    """A ray in the xy plane refracted into the prism's first face and out of the second, both
    by dielectric_sample with u1 = 0.9999 (past the Fresnel reflectance: the refracted lobe);
    returns the deviation angle (radians) per wavelength."""
    for i in range(lams.shape[0]):
        n = dispersion.ior_at(table.table[row], lams[i])
        # Apex up, symmetric about y: face 1's outward normal points up-left; the incoming ray
        # is -n1 turned counter-clockwise by the angle of incidence (towards the apex side).
        n1 = ti.math.vec2(-ti.cos(apex / 2.0), ti.sin(apex / 2.0))
        d_in = ti.math.vec2(ti.cos(incidence - apex / 2.0), ti.sin(incidence - apex / 2.0))
        d1 = _refract_2d(d_in, n1, n)
        n2 = ti.math.vec2(ti.cos(apex / 2.0), ti.sin(apex / 2.0))  # face 2's outward normal
        d2 = _refract_2d(d1, n2, 1.0 / n)
        out[i] = ti.acos(ti.math.clamp(d_in.dot(d2), -1.0, 1.0))


@ti.func
def _refract_2d(d, outward, eta):
    """Refract direction d through a face with outward normal `outward` (d enters against it when
    eta > 1, leaves along it when eta < 1) with the renderer's dielectric lobe in a local frame
    whose z is the normal on the incoming side."""
    normal = -outward if d.dot(outward) > 0.0 else outward  # the side wo (= -d) is on
    t = ti.math.vec2(normal.y, -normal.x)
    wo = ti.math.vec3(-d.dot(t), 0.0, -d.dot(normal))
    s = lobes.dielectric_sample(ti.math.vec3(1.0), 0.0, eta, wo, 0.9999, ti.math.vec2(0.5))
    return t * s.wi.x + normal * s.wi.z


def _table(spec):
    return MaterialTable.from_specs([spec])


@pytest.mark.parametrize("glass", sorted(SELLMEIER_PRESETS))
def test_sellmeier_presets_on_the_device(glass):
    spec = MaterialSpec(name="g", kind="dielectric", glass=glass)
    table = _table(spec)
    out = np.zeros_like(WAVELENGTHS)
    _ior_kernel(table, 0, WAVELENGTHS, out)
    np.testing.assert_allclose(out, dispersion.ior_at_np(spec, WAVELENGTHS), rtol=2e-6)
    assert np.all(np.diff(out) < 0.0)  # normal dispersion: blue bends more


def test_cauchy_from_abbe_hits_n_d_and_v():
    spec = MaterialSpec(name="flint", kind="dielectric", ior=1.62, abbe=36.0)
    n_d, n_f, n_c = dispersion.ior_at_np(spec, np.array([LINE_D, LINE_F, LINE_C]))
    assert abs(n_d - 1.62) < 1e-12 and abs((n_d - 1.0) / (n_f - n_c) - 36.0) < 1e-9


def test_prism_deviation_per_wavelength_follows_snell():
    spec = MaterialSpec(name="prism", kind="dielectric", glass="sf11")
    table = _table(spec)
    apex, incidence = math.radians(60.0), math.radians(70.0)  # no total reflection at 400 nm
    out = np.zeros_like(WAVELENGTHS)
    _prism_kernel(table, 0, WAVELENGTHS, incidence, apex, out)
    n = dispersion.ior_at_np(spec, WAVELENGTHS)
    inside = np.arcsin(np.sin(incidence) / n)
    exit_angle = np.arcsin(n * np.sin(apex - inside))
    expected = incidence + exit_angle - apex
    np.testing.assert_allclose(out, expected, atol=2e-5)  # f32 directions: ~1e-6 rad per refraction
    assert math.degrees(expected[0] - expected[-1]) > 3.0  # SF11 spreads 400-700 nm by degrees


GREY_GLASS = """
[scene]
geometry = "sdf"
[camera]
position = [0.0, 1.2, 3.0]
look_at = [0.0, 0.4, 0.0]
fov = 40
[render]
width = 24
height = 16
max_depth = 8
[environment]
type = "sky"
zenith = [0.6, 0.6, 0.6]
horizon = [1.0, 1.0, 1.0]
ground = [0.3, 0.3, 0.3]
[materials.floor]
type = "diffuse"
base_color = [0.5, 0.5, 0.5]
[materials.glass]
type = "dielectric"
base_color = [1.0, 1.0, 1.0]
roughness = 0.0
ior = 1.5
abbe = {abbe}
[[objects]]
type = "plane"
material = "floor"
[[objects]]
type = "sphere"
material = "glass"
radius = 0.45
translate = [0.0, 0.45, 0.0]
"""


def _render(scene, spp, seed):
    renderer = Renderer(scene)
    renderer.render(CameraFrame.from_spec(scene.camera), spp, integrator="mis", seed=seed)
    assert renderer.film.stats()["rejected"] == 0
    return renderer.image().astype(np.float64), renderer.film.variance_of_mean_image().astype(np.float64)


def test_constant_index_spectral_path_agrees_with_the_rgb_path(tmp_path):
    rgb = scene_from_toml(tmp_path, GREY_GLASS.format(abbe=0.0), "rgb")
    spectral = scene_from_toml(tmp_path, GREY_GLASS.format(abbe=1e9), "spectral")
    assert not scene_features(rgb).has_dispersion and scene_features(spectral).has_dispersion
    assert_agree(_render(rgb, 512, 3), _render(spectral, 512, 4), ("rgb", "spectral"))


def test_prism_scene_splits_white_light_into_a_spectrum():
    """The shipped prism scene: seen through SF11, the white slit turns into pixels that are
    strongly red and strongly blue, ordered along the image's vertical as the deviation says;
    the same prism with a constant index (its n_d) leaves every bright pixel neutral."""
    from dataclasses import replace

    from renderer.scene.catalog import load_any, resolve_scene

    scene = load_any(resolve_scene("prism"))
    scene = replace(scene, render=replace(scene.render, width=96, height=54))

    def bright_chromaticity(s):
        renderer = Renderer(s)
        renderer.render(CameraFrame.from_spec(s.camera), 64, integrator="mis", seed=11)
        image = renderer.image()
        total = image.sum(axis=2)
        bright = total > 0.25 * total.max()
        return image[bright] / total[bright][:, None], np.nonzero(bright)[0]

    chroma, rows = bright_chromaticity(scene)
    red, blue = chroma[:, 0] > 0.5, chroma[:, 2] > 0.5
    assert red.sum() >= 3 and blue.sum() >= 3, (red.sum(), blue.sum())
    # Shorter wavelengths deviate more, so the camera sees them higher up (smaller row numbers
    # here: row 0 is the top).
    assert rows[blue].mean() < rows[red].mean()
    plain = replace(scene, materials=tuple(dispersion.non_dispersive(m) for m in scene.materials))
    chroma, _ = bright_chromaticity(plain)
    assert chroma.max() < 0.45  # white stays white (within the noise of 64 spp)

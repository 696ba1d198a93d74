"""`path`, `nee` and `mis` estimate the same image; `sobol` and `independent` sample the same
integral; and all of them give pbrt's analytic cavity radiance.

Agreement of two images: Mitsuba's render-test rule (src/render/tests/test_renders.py), applied to
two Lantern renders on different seeds (independent estimates):
  - for every pixel and channel, z = (a - b) / sqrt(var_a + var_b), the variances being each film's
    variance of the pixel mean (s^2 / n), and its two-sided p-value 2 (1 - Phi(|z|));
  - significance ALPHA = 0.01 for the whole image, Sidak-corrected over its N pixels: a channel
    passes when p > 1 - (1 - ALPHA)^(1/N);
  - the images agree when (passing channels) / 3 >= 99.75 % of N.
  Pixels whose two variances are both 0 must be exactly equal.

The rule needs a near-normal pixel mean on both sides, i.e. many of the rare, high-value samples
per pixel; when they are rare, a pixel that happened to get none has a low mean *and* a low
variance estimate, and fails. Sizes and spp are chosen for that:
  - Cornell box at 16x16, max depth 8: `path` (BSDF sampling only) reaches the small ceiling light
    with a probability of a few percent per bounce, and the front of the short box is lit only by
    paths that find it after two or more bounces (tests/render/test_mitsuba_reference.py found
    that ~16k samples per 2x2 block of a 64x64 image are needed there). At 16x16, 8,192 spp (2M
    samples, ~2 s) give every pixel enough of those rare paths; `nee` and `mis` sample the light
    and need 2,048 spp.
  - Environment-lit scene (a diffuse and a glossy gold sphere on a floor, sphere traced), 32x24,
    max depth 6, under two maps. The gold's roughness is 0.5: `nee` takes the light the gold
    reflects from light samples alone, drawn in proportion to the map's brightness, so where a
    narrow lobe reflects a dim part of the map the rare light sample that lands in the lobe carries
    f / pdf_light large (heavy tail). At roughness 0.3 (GGX peak 1 / (pi alpha^2) = 39), 4 of 768
    pixels on and next to the gold failed nee against mis at 2,048 spp with p ~ 1e-8, nee low: its
    1,024-spp runs there ranged from 0.3 to 1.5 times the mean, but over 32 such runs on other
    seeds nee agreed with mis in every pixel (run-to-run variance, max |z| 3.7 of 768 pixels): a
    tail that one run's film variance misses, not a bias.
      venice.exr (peak 8.6; half the irradiance of an upward surface comes from ~18,000 texels,
      which a cosine-sampled direction hits with probability 0.38): no integrator, `path`
      included, has a heavy tail there, so all three pairs are tested (path 1,024 spp, nee 2,048
      (its glossy reflections come from light samples only, the noisiest of the three), mis 512).
      sky.exr (a sun of peak 22,672: half that irradiance comes from 3 texels, hit by a
      cosine-sampled direction with probability 7e-5): `path` would need ~10^5 samples per pixel
      before a pixel mean is near-normal (on average one sun hit per 14,000 samples), so under
      this map only `nee` against `mis` is tested: both importance-sample the map, which finds the
      sun with about half of the light samples, and MIS weighs the BSDF samples that hit it down
      (nee drops them), so their samples are bounded: mis at 512 spp; nee at 2,048, for the same
      glossy tail as above (at 512 spp one pixel on top of the gold failed with p 3e-9, nee low,
      while 24 runs on other seeds showed no bias there: max |z| 3.5 of 768 pixels).
  - Sobol against independent: `mis` under venice.exr. The film's variance treats the Sobol
    samples of a pixel as independent; for scrambled nets that usually overestimates the variance
    of the mean, which makes the test conservative on the Sobol side, not invalid.

Analytic cavity (pbrt's test): inside a closed diffuse cavity of albedo a emitting Le, every
radiance is Le / (1 - a) = 1 here (a = 0.7, Le = 0.3, so paths of ~3 bounces and Russian roulette
are exercised). The image mean of one channel (green; the channels of a grey scene are the same
numbers) is z-tested against 1 at ALPHA = 0.01, two-sided, with var = sum(var of pixel means) / N^2
(pixels are independent), for every integrator and sampler, on two cavities:
  - sphere traced: a box minus a sphere (tests/scene_builder.cavity_toml). The SDF wall is not an
    emitter the lights can sample, so `nee` and `mis` reduce to BSDF sampling there;
  - triangle mesh: an icosphere (1,280 triangles) with reversed winding, so the front faces (the
    emitting side) face the inside, loaded from an OBJ without normals (flat shading, so the
    shading normal is the geometric one and every bounce has albedo exactly a). Its triangles are
    emitters that `nee` and `mis` sample (through the light tree, with that many emitters).

Every agreement test also z-tests the two image means (green, ALPHA two-sided): a small bias
spread over the whole image hides from the per-pixel rule but not from the mean of all pixels.
Seeds are fixed; every comparison uses different seeds on its two sides.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from tests.scene_builder import MESH_CAVITY, cavity_toml, scene_from_toml
from tests.stats.image_tests import assert_agree, mean_z

ALPHA = 0.01  # significance level of every test here (the per-pixel rule Sidak-corrects it)
SAMPLERS = ("independent", "sobol")
INTEGRATORS = ("path", "nee", "mis")
SEEDS = {"path": 101, "nee": 202, "mis": 303}  # different seeds: the two sides are independent
SOBOL_SEED = 404

CORNELL_SIZE = (16, 16)
CORNELL_SPP = {"path": 8192, "nee": 2048, "mis": 2048}
ENV_SPP = {"path": 1024, "nee": 2048, "mis": 512}
SKY_SPP = {"nee": 2048, "mis": 512}

CAVITY_ALBEDO = 0.7
CAVITY_EMISSION = 0.3
CAVITY_EXPECTED = CAVITY_EMISSION / (1.0 - CAVITY_ALBEDO)
CAVITY_SPP = 256

ENV_SCENE = """
[scene]
geometry = "sdf"
[camera]
position = [0.0, 1.2, 3.2]
look_at = [0.0, 0.45, 0.0]
fov = 40
[render]
width = 32
height = 24
max_depth = 6
[environment]
type = "map"
file = "{env}"
[materials.floor]
type = "diffuse"
base_color = [0.5, 0.5, 0.5]
[materials.clay]
type = "diffuse"
base_color = [0.7, 0.6, 0.5]
[materials.gold]
type = "conductor"
base_color = [1.0, 0.78, 0.34]
roughness = 0.5
[[objects]]
type = "plane"
material = "floor"
[[objects]]
type = "sphere"
material = "clay"
radius = 0.45
translate = [-0.55, 0.45, 0.0]
[[objects]]
type = "sphere"
material = "gold"
radius = 0.45
translate = [0.55, 0.45, 0.0]
"""



# --- renders -------------------------------------------------------------------------------------

class Renders:
    """One Renderer per scene (programs compile once per Renderer) and its renders, cached."""

    def __init__(self, scene, size=None):
        self.scene = scene
        self.renderer = Renderer(scene, size)
        self.camera = CameraFrame.from_spec(scene.camera)
        self._done = {}

    def __call__(self, integrator, spp, seed, sampler="independent"):
        key = (integrator, spp, seed, sampler)
        if key not in self._done:
            r = self.renderer
            r.reset()
            r.render(self.camera, spp, integrator, seed=seed, sampler=sampler)
            assert r.film.stats()["rejected"] == 0, f"{integrator}/{sampler}: non-finite samples"
            self._done[key] = (r.film.mean_image().astype(np.float64),
                               r.film.variance_of_mean_image().astype(np.float64))
        return self._done[key]


ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def cornell():
    from renderer.scene import load_scene

    return Renders(load_scene(ROOT / "assets" / "scenes" / "cornell_box.toml"), CORNELL_SIZE)


def _env_scene(tmp_path_factory, name):
    """ENV_SCENE under assets/envmaps/<name>.exr (its few negative texels are clamped, with a warning)."""
    path = ROOT / "assets" / "envmaps" / f"{name}.exr"
    return scene_from_toml(tmp_path_factory.mktemp(f"env_{name}"), ENV_SCENE.format(env=path.as_posix()), name)


@pytest.fixture(scope="module")
def venice(tmp_path_factory):
    return Renders(_env_scene(tmp_path_factory, "venice"))


@pytest.fixture(scope="module")
def sky(tmp_path_factory):
    return Renders(_env_scene(tmp_path_factory, "sky"))


def icosphere_cavity_obj(path, subdivisions=3):
    """An icosphere whose triangles face inwards, as an OBJ without normals (flat shading)."""
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    inward = trimesh.Trimesh(sphere.vertices, sphere.faces[:, ::-1], process=False)
    path.write_text(trimesh.exchange.obj.export_obj(inward, include_normals=False, include_texture=False))
    return path


@pytest.fixture(scope="module")
def sdf_cavity(tmp_path_factory):
    scene = scene_from_toml(tmp_path_factory.mktemp("sdf_cavity"), cavity_toml(CAVITY_ALBEDO, CAVITY_EMISSION))
    return Renders(scene)


@pytest.fixture(scope="module")
def mesh_cavity(tmp_path_factory):
    folder = tmp_path_factory.mktemp("mesh_cavity")
    obj = icosphere_cavity_obj(folder / "cavity.obj")
    body = MESH_CAVITY.format(albedo=CAVITY_ALBEDO, emission=CAVITY_EMISSION, obj=obj.as_posix())
    return Renders(scene_from_toml(folder, body))


# --- tests ---------------------------------------------------------------------------------------

PAIRS = [("path", "mis"), ("nee", "mis"), ("nee", "path")]


@pytest.mark.parametrize("a,b", PAIRS, ids=[f"{a}-{b}" for a, b in PAIRS])
def test_cornell_box_integrators_agree(cornell, a, b):
    ra = cornell(a, CORNELL_SPP[a], SEEDS[a])
    rb = cornell(b, CORNELL_SPP[b], SEEDS[b])
    assert_agree(ra, rb, (a, b))


@pytest.mark.parametrize("a,b", PAIRS, ids=[f"{a}-{b}" for a, b in PAIRS])
def test_environment_lit_integrators_agree(venice, a, b):
    ra = venice(a, ENV_SPP[a], SEEDS[a])
    rb = venice(b, ENV_SPP[b], SEEDS[b])
    assert_agree(ra, rb, (a, b))


def test_nee_and_mis_agree_under_a_sun_of_peak_ten_thousand(sky):
    assert_agree(sky("nee", SKY_SPP["nee"], SEEDS["nee"]), sky("mis", SKY_SPP["mis"], SEEDS["mis"]), ("nee", "mis"))


def test_sobol_agrees_with_independent(venice):
    ra = venice("mis", ENV_SPP["mis"], SOBOL_SEED, sampler="sobol")
    rb = venice("mis", ENV_SPP["mis"], SEEDS["mis"])
    assert_agree(ra, rb, ("mis/sobol", "mis/independent"))


CAVITY_CASES = [(i, s) for i in INTEGRATORS for s in SAMPLERS]


@pytest.mark.parametrize("integrator,sampler", CAVITY_CASES, ids=[f"{i}-{s}" for i, s in CAVITY_CASES])
@pytest.mark.parametrize("kind", ["sdf", "mesh"])
def test_analytic_cavity_for_every_integrator_and_sampler(kind, integrator, sampler, request):
    renders = request.getfixturevalue(f"{kind}_cavity")
    mean, var = renders(integrator, CAVITY_SPP, SEEDS[integrator], sampler)
    z = mean_z(mean, var, CAVITY_EXPECTED)
    critical = stats.norm.isf(ALPHA / 2)
    assert abs(z) < critical, (f"{kind} cavity, {integrator}/{sampler}: image mean (green) "
                               f"{mean[..., 1].mean():.5f}, expected {CAVITY_EXPECTED} (z = {z:.2f}, critical {critical:.2f})")


def test_mesh_cavity_emitters_are_light_sampled(mesh_cavity):
    """The mesh cavity tests what it means to: its triangles are emitters the lights sample."""
    lights = mesh_cavity.renderer.lights()
    assert lights.count == 1280

"""An environment turned by any rotation R (EnvironmentSpec.needs_matrix, renderer/lights/environment.py):
its lookup at d is the unturned lookup at R^T d, its sampler draws R times the unturned sampler's
directions with the same pdf, the sampler agrees with its pdf (chi-square), its estimator of the
map's integral stays unbiased, only such orientations compile the matrix in, and the lookup is
Mitsuba 3's `envmap` `eval` under the same to_world, a mirror included (when Mitsuba is installed).

Statistics: alpha = 0.01 with a Sidak correction over NUM_TESTS tests in this file (3 chi-square
tests, the chi-square's power check, 3 z-tests); fixed seeds, so each outcome is deterministic.
"""
import math
import warnings

import numpy as np
import pytest
from scipy import stats

from renderer.lights.env_sampling import EnvironmentSampler
from renderer.lights.environment import Environment
from renderer.output.image_io import read_environment, write_exr
from renderer.scene.description import EnvironmentSpec
from tests.lights.test_env_sampling import exact_integral
from tests.stats.chi2 import ENV_FRAME, chi2_test, sidak_alpha

ALPHA = 0.01
NUM_TESTS = 7
N = 1_000_000
TILTED_AXIS = tuple(np.array([0.3, 0.5, -0.8]) / np.linalg.norm([0.3, 0.5, -0.8]))


def tilted(degrees=50.0):
    return EnvironmentSpec(kind="map", rotation=degrees, rotation_axis=TILTED_AXIS)


def quarter_about_x():
    """The map's zenith seen along +z: its poles lie in the horizon."""
    return EnvironmentSpec(kind="map", rotation=90.0, rotation_axis=(1.0, 0.0, 0.0))


def mirrored():
    """A to_world with a mirror (det -1), as a Mitsuba file may give: Mitsuba mirrors the map."""
    m = tilted(-70.0).rotation_matrix() @ np.diag([1.0, 1.0, -1.0])
    return EnvironmentSpec(kind="map", to_world=tuple(tuple(float(x) for x in row) for row in m))


ORIENTATIONS = {"tilted": tilted, "quarter_about_x": quarter_about_x, "mirrored": mirrored}


def random_map(seed=3, height=16, width=32):
    """Random texels in [0, 4); the first and last rows constant, as a map of the sphere has them
    (they are its poles, where every azimuth meets)."""
    image = np.random.default_rng(seed).random((height, width, 3)) * 4.0
    image[0], image[-1] = image[0].mean(axis=0), image[-1].mean(axis=0)
    return image.astype(np.float32)


def one_hot(height=32, width=64, row=3, col=20, value=1000.0):
    """A hot texel near the map's zenith: turned, it shines from far off the world's pole."""
    image = np.zeros((height, width, 3), np.float32)
    image[row, col] = value
    return image


def studio():
    with warnings.catch_warnings():  # lossy-compression ringing clamped to 0: expected here
        warnings.simplefilter("ignore")
        return read_environment("assets/envmaps/studio.exr")


def sampler(image, spec):
    return EnvironmentSampler(image, Environment(spec, image))


def unit_directions(seed, n):
    d = np.random.default_rng(seed).normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def uniforms(seed, n=N):
    return np.random.default_rng(seed).random((n, 2), dtype=np.float32)


def map_frame(spec):
    """The chi-square harness's frame for the map's own (phi, theta) in world coordinates: rows
    ENV_FRAME R^T, so the pdf's texel edges are the harness's break lines and its quadrature exact."""
    return ENV_FRAME @ spec.rotation_matrix().T


# -- lookup and sampling against the unturned map ------------------------------------------------

@pytest.mark.parametrize("name", list(ORIENTATIONS))
def test_lookup_is_the_unturned_lookup_at_the_turned_direction(taichi_runtime, name):
    """radiance_R(d) = radiance(R^T d) on random directions and around the map's poles, to float32
    rounding: the kernel's R^T d differs from numpy's by ~1e-7, an azimuth error that grows as
    1 / sin(theta) towards the map's poles, times the map's slope (~20 per radian here)."""
    spec = ORIENTATIONS[name]()
    image = random_map()
    turned, plain = sampler(image, spec), sampler(image, EnvironmentSpec(kind="map"))
    assert turned.environment.rotated and not plain.environment.rotated
    r = spec.rotation_matrix()
    poles = np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [1e-4, 1.0, 0.0], [0.0, -1.0, 1e-4]]) @ r.T
    d = np.concatenate([unit_directions(1, 20_000), poles])
    local = d @ r
    sin_theta = np.hypot(local[:, 0], local[:, 2])
    error = np.abs(turned.radiance_batch(d) - plain.radiance_batch(local)).max(axis=1)
    tolerance = 4e-5 + 2e-6 / np.maximum(sin_theta, 1e-6)  # at a pole itself: the check below
    assert (error <= tolerance).all(), (error / tolerance).max()
    # the map's zenith is seen along R +y
    np.testing.assert_allclose(turned.radiance_batch(r[:, 1][None])[0], image[0, 0], rtol=1e-5)


def test_a_turned_sky_is_the_sky_at_the_turned_direction(taichi_runtime):
    """The sky's gradient turns with its axis too (a constant colour has nothing to turn)."""
    spec = EnvironmentSpec(kind="sky", rotation=90.0, rotation_axis=(1.0, 0.0, 0.0))
    turned = Environment(spec, None)
    assert turned.rotated
    plain = Environment(EnvironmentSpec(kind="sky"), None)
    d = unit_directions(2, 5000)
    a, b = radiance_of(turned, d), radiance_of(plain, d @ spec.rotation_matrix())
    np.testing.assert_allclose(a, b, rtol=0.0, atol=1e-5)
    # the sky's zenith colour is seen along +z
    np.testing.assert_allclose(radiance_of(turned, np.array([[0.0, 0.0, 1.0]]))[0], spec.zenith, atol=1e-6)


def radiance_of(environment, directions):
    import taichi as ti

    d = np.ascontiguousarray(directions, np.float32)
    out = np.zeros_like(d)

    @ti.kernel
    def lookup(d: ti.types.ndarray(dtype=ti.math.vec3, ndim=1), out: ti.types.ndarray(dtype=ti.math.vec3, ndim=1)):
        for k in range(d.shape[0]):
            out[k] = environment.radiance(d[k])

    lookup(d, out)
    return out


@pytest.mark.parametrize("name", list(ORIENTATIONS))
def test_sampler_draws_the_turned_samples_with_the_same_pdf(taichi_runtime, name):
    """The same uniforms give R times the unturned direction, the same pdf (a rotation's Jacobian is
    1) and the radiance there; pdf(d) agrees with the sample's pdf away from texel borders."""
    spec = ORIENTATIONS[name]()
    image = random_map(5)
    turned, plain = sampler(image, spec), sampler(image, EnvironmentSpec(kind="map"))
    u = uniforms(6, 50_000)
    d, pdf, radiance = turned.sample_batch(u)
    d0, pdf0, _ = plain.sample_batch(u)
    r = spec.rotation_matrix()
    np.testing.assert_allclose(d, d0 @ r.T, rtol=0.0, atol=1e-6)
    np.testing.assert_array_equal(pdf, pdf0)
    # the radiance at the sample: the kernel turns the direction back itself, in registers, where
    # its atan2 may round a few float32 ulps (1e-6 rad) otherwise than from the stored direction
    np.testing.assert_allclose(radiance, turned.radiance_batch(d), rtol=0.0, atol=1e-4)
    again = turned.pdf_batch(d)
    assert np.mean(again == pdf) > 0.999  # at a texel border a rounded direction may see its neighbour
    np.testing.assert_allclose(again, plain.pdf_batch(d @ r), rtol=0.0, atol=0.0)


# -- the sampler against its pdf ------------------------------------------------------------------

CHI2_CASES = [("one_hot", "tilted", 11), ("studio", "quarter_about_x", 12), ("studio", "mirrored", 13)]


@pytest.mark.parametrize("image_name, orientation, seed", CHI2_CASES)
def test_chi2_turned(taichi_runtime, tmp_path, image_name, orientation, seed):
    """The turned sampler's directions against its own pdf, binned in the map's frame (where the
    pdf is piecewise constant between the break lines: exact expected counts)."""
    spec = ORIENTATIONS[orientation]()
    s = sampler(one_hot() if image_name == "one_hot" else studio(), spec)
    d, _, _ = s.sample_batch(uniforms(seed))
    phi, theta = s.texel_edges()
    result = chi2_test(d, s.pdf_batch, frame=map_frame(spec), res=64, subdivisions=1, phi_breaks=phi,
                       theta_breaks=theta, alpha=ALPHA, num_tests=NUM_TESTS)
    if not result.passed:
        result.write_png(tmp_path / f"{image_name}_{orientation}.png")
    assert result.passed, result.report
    assert result.pdf_integral == pytest.approx(1.0, abs=1e-5)


def test_chi2_sees_a_rotation_applied_the_wrong_way(taichi_runtime):
    """A pdf that turns by R where the sampler turns by R^T (the inverse mix-up) is rejected."""
    spec = tilted()
    image = studio()
    turned, plain = sampler(image, spec), sampler(image, EnvironmentSpec(kind="map"))
    r = spec.rotation_matrix()
    d, _, _ = turned.sample_batch(uniforms(14))
    phi, theta = turned.texel_edges()
    result = chi2_test(d, lambda x: plain.pdf_batch(x @ r.T), frame=map_frame(spec), res=64, subdivisions=1,
                       phi_breaks=phi, theta_breaks=theta, alpha=ALPHA, num_tests=NUM_TESTS)
    assert not result.passed and result.p_value < 1e-100, result.report


def test_estimator_is_unbiased_when_turned(taichi_runtime):
    """z-test per channel: the mean of radiance / pdf of the turned sampler against the exact
    integral of the unturned map (a rotation leaves the integral over the sphere as it is)."""
    image = studio()
    turned, plain = sampler(image, tilted(123.0)), sampler(image, EnvironmentSpec(kind="map"))
    turned.environment.scalars[0] = plain.environment.scalars[0] = 1.5
    reference = exact_integral(plain)
    _, pdf, radiance = turned.sample_batch(uniforms(15))
    estimates = radiance.astype(np.float64) / pdf.astype(np.float64)[:, None]
    mean = estimates.mean(axis=0)
    z = (mean - reference) / (estimates.std(axis=0, ddof=1) / math.sqrt(len(estimates)))
    p_values = 2.0 * stats.norm.sf(np.abs(z))
    assert (p_values >= sidak_alpha(ALPHA, NUM_TESTS)).all(), (reference, mean, z)


# -- what compiles -------------------------------------------------------------------------------

def test_only_a_rotation_off_the_pole_compiles_the_matrix(taichi_runtime):
    """A turn about +y (by `rotation`, an axis along -y, or a to_world that is one) stays the azimuth
    offset, as before the matrix existed; so does any orientation of a constant colour."""
    image = random_map()
    about_y = EnvironmentSpec(kind="map", rotation=30.0).rotation_matrix()
    for spec, angle in [(EnvironmentSpec(kind="map", rotation=30.0), 30.0),
                        (EnvironmentSpec(kind="map", rotation=30.0, rotation_axis=(0.0, -1.0, 0.0)), -30.0),
                        (EnvironmentSpec(kind="map", to_world=tuple(map(tuple, about_y))), 30.0),
                        (EnvironmentSpec(kind="map", rotation=360.0, rotation_axis=TILTED_AXIS), 0.0)]:
        env = Environment(spec, image)
        assert not spec.needs_matrix and not env.rotated and not hasattr(env, "frame"), spec
        assert env.scalars[1] == pytest.approx(math.radians(angle), abs=1e-6)
    constant = EnvironmentSpec(kind="constant", rotation=40.0, rotation_axis=(1.0, 0.0, 0.0))
    assert not constant.needs_matrix and not Environment(constant, None).rotated
    env = Environment(tilted(), image)
    assert env.rotated and env.scalars[1] == 0.0  # the matrix carries all of the orientation
    np.testing.assert_allclose(env.frame[None].to_numpy(), tilted().rotation_matrix(), atol=1e-7)
    env.set_spec(quarter_about_x())  # a rotated environment takes any orientation as data
    np.testing.assert_allclose(env.frame[None].to_numpy(), quarter_about_x().rotation_matrix(), atol=1e-7)
    with pytest.raises(ValueError, match="turns about \\+y only"):
        Environment(EnvironmentSpec(kind="map", rotation=30.0), image).set_spec(tilted())


# -- against Mitsuba -------------------------------------------------------------------------------

@pytest.mark.parametrize("name", list(ORIENTATIONS))
def test_lookup_is_mitsubas_envmap(taichi_runtime, tmp_path, name):
    """Mitsuba 3's envmap `eval` (scalar_rgb, the same EXR, to_world = the spec's matrix) at 300
    random directions equals Lantern's lookup to float32 rounding."""
    mi = pytest.importorskip("mitsuba", reason="Mitsuba is the project's optional `reference` extra")
    mi.set_variant("scalar_rgb")
    spec = ORIENTATIONS[name]()
    path = tmp_path / "map.exr"
    write_exr(path, random_map(7, 8, 16))
    image = read_environment(path)
    m = np.eye(4)
    m[:3, :3] = spec.rotation_matrix()
    emitter = mi.load_dict({"type": "envmap", "filename": str(path), "to_world": mi.ScalarTransform4f(m.tolist())})
    d = unit_directions(8, 300)
    theirs = []
    for v in d:
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*(-v))  # eval looks along -wi
        theirs.append(np.array(emitter.eval(si)))
    np.testing.assert_allclose(sampler(image, spec).radiance_batch(d), np.array(theirs), rtol=0.0, atol=2e-5)

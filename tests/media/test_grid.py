"""Grid media (renderer/media/grid.py, grid_table.py): lookups against the numpy reference, ratio
tracking's transmittance and delta tracking's distances and weights against closed forms.

The test medium is a ramp: density a_c + b_c u along the grid's local x (u in [0, 1]), constant in
y and z. Trilinear interpolation of a linear function between the cell centres is that function,
and clamping holds it constant beyond the first and last centre, so its integral along any ray is
known exactly (`optical_depth`, piecewise linear in the world x).

Statistical tests: fixed seeds, ALPHA = 0.01 family-wise over the module's NUM_TESTS tests
(Sidak-corrected); means are z-tested against their exact values with the sample's own standard
error, the free-flight distances by a Kolmogorov-Smirnov test against their exact CDF.
"""
import math

import numpy as np
import pytest
import taichi as ti
from scipy import stats

from renderer.geometry.interface import Ray
from renderer.media import grid
from renderer.media.grid_table import GridMedia
from renderer.sampling.rng import SampleState, sample_key
from renderer.scene.description import MediumSpec, VolumeGridSpec
from tests.stats.chi2 import sidak_alpha

vec3 = ti.math.vec3
ALPHA = 0.01
N = 200_000
NX = 8  # ramp cells along x
RAMP_A = np.array([0.2, 1.0, 0.0])  # density at u = 0, per channel
RAMP_B = np.array([1.5, -0.8, 2.0])  # its slope along u
SCALE = 1.7
# The grid's box: [-1, 1] x [-0.5, 0.5] x [0, 1] (local x stretched by 2).
TO_WORLD = np.array([[2.0, 0.0, 0.0, -1.0], [0.0, 1.0, 0.0, -0.5], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
RAYS = (  # (origin, direction (unit), t_end)
    ((-3.0, 0.1, 0.5), (1.0, 0.0, 0.0), 10.0),  # through the whole box
    ((-0.6, 0.0, 0.3), (0.6, 0.0, 0.8), 0.5),  # from inside, ending inside
    ((1.5, 0.8, 0.2), (-0.8, -0.6, 0.0), math.inf),  # obliquely, into the open
)
ALBEDO = np.array([0.9, 0.5, 0.2])
THROUGHPUT = (1.0, 0.3, 0.05)  # a path's colour so far: steers the spectral tracking, not its mean
NUM_TESTS = len(RAYS) * (3 + 2 + 9)  # ratio tracking, grey delta tracking, spectral tracking


def ramp_values(channels=3):
    u = (np.arange(NX) + 0.5) / NX
    values = RAMP_A[None, :] + RAMP_B[None, :] * u[:, None]  # (x, channel)
    return np.broadcast_to(values[None, None, :, :channels], (2, 3, NX, channels)).astype(np.float32).copy()


def ramp_medium(albedo=ALBEDO, channels=3):
    density = VolumeGridSpec(ramp_values(channels), to_world=tuple(map(tuple, TO_WORLD)))
    albedo_grid = VolumeGridSpec(np.array(albedo, np.float32).reshape(1, 1, 1, 3), constant=tuple(albedo))
    return MediumSpec("ramp", sigma_s=(0.0, 0.0, 0.0), kind="grid", density=density, albedo=albedo_grid,
                      scale=SCALE)


def sigma_t_np(points, channels=3):
    """The ramp's extinction at world points (N, 3), zero outside its box."""
    u = (points[:, 0] + 1.0) / 2.0
    inside = (np.abs(points[:, 0]) <= 1.0) & (np.abs(points[:, 1]) <= 0.5) & (points[:, 2] >= 0) & (points[:, 2] <= 1)
    uc = np.clip(u, 0.5 / NX, 1.0 - 0.5 / NX)
    sigma = SCALE * (RAMP_A[None, :channels] + RAMP_B[None, :channels] * uc[:, None])
    return np.where(inside[:, None], sigma, 0.0)


def optical_depth(o, d, t):
    """integral_0^t sigma_t(o + s d) ds per channel, for each t of an increasing array: the
    integrand is piecewise linear in s with breaks where the box or the clamping begins or ends,
    so the midpoint rule over a grid holding every break is exact (the box's faces are jumps,
    which only ever fall between two pieces)."""
    o, d = np.asarray(o), np.asarray(d)
    breaks = [0.0]
    for a, faces in ((0, (-1.0, 1.0, -1.0 + 1.0 / NX, 1.0 - 1.0 / NX)), (1, (-0.5, 0.5)), (2, (0.0, 1.0))):
        if d[a] != 0.0:
            breaks += [(f - o[a]) / d[a] for f in faces]
    end = float(np.max(t))
    s = np.unique(np.clip(np.r_[breaks, np.linspace(0.0, end, 20001), t], 0.0, end))
    mid = sigma_t_np(o + 0.5 * (s[1:] + s[:-1])[:, None] * d)
    cumulative = np.r_[np.zeros((1, 3)), np.cumsum(mid * np.diff(s)[:, None], axis=0)]
    return np.stack([np.interp(t, s, cumulative[:, c]) for c in range(3)], axis=-1)


@ti.kernel
def _track(grids: ti.template(), o: vec3, d: vec3, t_end: ti.f32, throughput: vec3, seed: ti.u32,
           tr: ti.types.ndarray(dtype=vec3, ndim=1), t: ti.types.ndarray(dtype=ti.f32, ndim=1),
           scattered: ti.types.ndarray(dtype=ti.i32, ndim=1), weight: ti.types.ndarray(dtype=vec3, ndim=1)):
    for i in range(tr.shape[0]):
        state = SampleState(pixel=ti.u32(i), index=ti.u32(0), seed=seed, key=sample_key(i, 0, seed))
        ray = Ray(o=o, d=d, cone_width=0.0, cone_spread=0.0)
        tr[i] = grids.transmittance(0, ray, t_end, grid.tracking_key(state, 3, 0))
        s = grids.free_flight(0, ray, t_end, throughput, grid.tracking_key(state, 4, 0))
        t[i] = s.t
        scattered[i] = s.scattered
        weight[i] = s.weight


@ti.kernel
def _lookup(grids: ti.template(), index: ti.i32, points: ti.types.ndarray(dtype=vec3, ndim=1),
            out: ti.types.ndarray(dtype=vec3, ndim=1)):
    for i in range(points.shape[0]):
        out[i] = grid.lookup(grids.volumes, grids.voxels, index, points[i])


def track(medium, ray, seed, throughput=(1.0, 1.0, 1.0), n=N):
    grids = GridMedia([medium])
    o, d, t_end = ray
    tr, w = np.zeros((n, 3), np.float32), np.zeros((n, 3), np.float32)
    t, scattered = np.zeros(n, np.float32), np.zeros(n, np.int32)
    _track(grids, vec3(*o), vec3(*d), min(t_end, 3e38), vec3(*throughput), seed, tr, t, scattered, w)
    return tr.astype(np.float64), t.astype(np.float64), scattered.astype(bool), w.astype(np.float64)


def p_value(values, expected):
    sem = values.std(ddof=1) / math.sqrt(len(values))
    if sem == 0.0:
        return 1.0 if abs(values.mean() - expected) <= 1e-6 else 0.0
    return 2.0 * stats.norm.sf(abs(values.mean() - expected) / sem)


def box_exit(o, d, t_end):
    """Where the ray leaves the box (or t_end): the last place a collision can happen."""
    t0, t1 = 0.0, t_end
    for a, (lo, hi) in enumerate(((-1.0, 1.0), (-0.5, 0.5), (0.0, 1.0))):
        if d[a] != 0.0:
            ta, tb = (lo - o[a]) / d[a], (hi - o[a]) / d[a]
            t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
    return t0, t1


@pytest.mark.parametrize("nearest", [False, True])
@pytest.mark.parametrize("channels", [1, 3])
def test_lookups_match_the_numpy_reference(nearest, channels):
    rng = np.random.default_rng(11 + channels)
    values = rng.random((3, 4, 5, channels)).astype(np.float32)
    angle = 0.7
    to_world = np.array([[math.cos(angle), -math.sin(angle), 0.0, 0.3], [math.sin(angle), math.cos(angle), 0.0, -0.2],
                         [0.0, 0.0, 1.5, 0.1], [0.0, 0.0, 0.0, 1.0]]) @ np.diag([1.2, 0.8, 1.0, 1.0])
    spec = VolumeGridSpec(values, to_world=tuple(map(tuple, to_world)), nearest=nearest)
    medium = MediumSpec("m", kind="grid", density=spec, albedo=spec)
    grids = GridMedia([MediumSpec("plain"), medium])  # a homogeneous medium first: rows keep their order
    local = rng.uniform(-0.2, 1.2, (4000, 3))  # inside the box and around it (clamped)
    points = (np.c_[local, np.ones(len(local))] @ to_world.T)[:, :3]
    out = np.zeros((len(points), 3), np.float32)
    _lookup(grids, 0, points.astype(np.float32), out)
    expected = grid.lookup_np(values, np.linalg.inv(to_world), points, nearest)
    away = np.min(np.abs(local * np.array([5, 4, 3]) - np.round(local * np.array([5, 4, 3]))), axis=1) > 1e-3
    check = away if nearest else slice(None)  # (nearest: not where f32 rounding may pick the next voxel)
    np.testing.assert_allclose(out[check], np.broadcast_to(expected, (len(points), 3))[check], rtol=2e-5, atol=2e-6)


@pytest.mark.parametrize("ray", range(len(RAYS)))
def test_ratio_tracking_is_the_exact_transmittance(ray):
    o, d, t_end = RAYS[ray]
    tr, *_ = track(ramp_medium(), RAYS[ray], seed=100 + ray)
    t0, t1 = box_exit(o, d, t_end)
    expected = np.exp(-optical_depth(o, d, np.array([t1]))[0])
    assert 0.01 < expected.min() and expected.max() < 0.99  # the rays see the medium, not all of it
    assert np.all((tr >= 0.0) & (tr <= 1.0))
    for c in range(3):
        p = p_value(tr[:, c], expected[c])
        assert p >= sidak_alpha(ALPHA, NUM_TESTS), f"channel {c}: {tr[:, c].mean():.5f} vs {expected[c]:.5f}"


@pytest.mark.parametrize("ray", range(len(RAYS)))
def test_delta_tracking_distances_follow_the_grey_density(ray):
    """Albedo 1 and a grey ramp: plain delta tracking, every weight 1. It escapes with probability
    exp(-tau(t1)) (a binomial z-test) and collides at t with the density sigma_t(t) exp(-tau(t)),
    whose CDF conditioned on colliding, (1 - exp(-tau(t))) / (1 - exp(-tau(t1))), the KS test checks."""
    o, d, t_end = RAYS[ray]
    _, t, scattered, weight = track(ramp_medium(albedo=(1.0, 1.0, 1.0), channels=1), RAYS[ray], seed=200 + ray)
    np.testing.assert_allclose(weight, 1.0, rtol=1e-5)
    t0, t1 = box_exit(o, d, t_end)
    assert np.all((t[scattered] >= t0) & (t[scattered] <= t1)) and np.all(t[~scattered] == np.float32(min(t_end, 3e38)))
    grid_t = np.linspace(0.0, t1, 4001)
    tau = optical_depth(o, d, grid_t)[:, 0]
    escape = math.exp(-tau[-1])
    z = ((~scattered).mean() - escape) / math.sqrt(escape * (1.0 - escape) / N)
    alpha = sidak_alpha(ALPHA, NUM_TESTS)
    assert 2.0 * stats.norm.sf(abs(z)) >= alpha, f"escaped {(~scattered).mean():.5f} vs {escape:.5f}"
    cdf = lambda x: np.interp(x, grid_t, -np.expm1(-tau)) / (1.0 - escape)
    assert stats.kstest(t[scattered], cdf).pvalue >= alpha


@pytest.mark.parametrize("ray", range(len(RAYS)))
def test_spectral_tracking_weights_are_unbiased(ray):
    """A chromatic ramp and albedo, with a path colour steering the choice: per channel
    E[weight; no collision] = T(t1) and E[weight; collision] = albedo (1 - T(t1)), the
    single-scattered fraction (integral of sigma_s T over the segment)."""
    o, d, t_end = RAYS[ray]
    _, t, scattered, weight = track(ramp_medium(), RAYS[ray], seed=300 + ray, throughput=THROUGHPUT)
    assert np.all(np.isfinite(weight)) and np.all(weight >= 0.0)
    _, t1 = box_exit(o, d, t_end)
    tr = np.exp(-optical_depth(o, d, np.array([t1]))[0])
    alpha = sidak_alpha(ALPHA, NUM_TESTS)
    for c in range(3):
        surface = np.where(scattered, 0.0, weight[:, c])
        collided = np.where(scattered, weight[:, c], 0.0)
        assert p_value(surface, tr[c]) >= alpha, f"channel {c}: surface {surface.mean():.5f} vs {tr[c]:.5f}"
        single = ALBEDO[c] * (1.0 - tr[c])
        assert p_value(collided, single) >= alpha, f"channel {c}: collided {collided.mean():.5f} vs {single:.5f}"
        # And where along the ray: the first half of the collisions (by the median distance).
        half = np.median(t[scattered])
        early = np.where(scattered & (t < half), weight[:, c], 0.0)
        expected = ALBEDO[c] * -np.expm1(-optical_depth(o, d, np.array([half]))[0][c])
        assert p_value(early, expected) >= alpha, f"channel {c}: early {early.mean():.5f} vs {expected:.5f}"


def test_an_empty_grid_neither_scatters_nor_attenuates():
    """A grid of zeros has majorant 0: no steps, transmittance 1, the surface reached at weight 1."""
    zero = VolumeGridSpec(np.zeros((1, 1, 1, 1), np.float32), to_world=tuple(map(tuple, TO_WORLD)))
    medium = MediumSpec("empty", kind="grid", density=zero, albedo=zero)
    tr, t, scattered, weight = track(medium, RAYS[0], seed=1, n=64)
    assert np.all(tr == 1.0) and not scattered.any() and np.all(weight == 1.0) and np.all(t == 10.0)

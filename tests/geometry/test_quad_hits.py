"""Quad hits are right from both sides, and the leaf test's precomputed form (`quad_framed` with
the rows of `quad_frames`) agrees with the plain one (`quad`).

Random parallelograms of 1 mm, 1 m and 1 km, at the origin and 1 km away, hit from both sides at
random incidences: rays aimed inside (coordinates a, b in [0.02, 0.98]) hit, with t, a and b equal
to the exact (float64) intersection of the same f32 ray and quad within the f32 bound of
tests/geometry/hit_bounds.py (a quad is two triangles of its conditioning), and the point
corner + a edge_u + b edge_v equal to o + t d within it; rays aimed outside (a or b 5 % or more
beyond [0, 1]) miss. Both forms agree on every hit flag.
"""
import numpy as np
import pytest
import taichi as ti

from renderer.geometry import intersect as isect
from renderer.geometry.interface import INF
from tests.geometry.hit_bounds import exact_triangle_hit, tilted, triangle_tolerance, unit

vec3 = ti.math.vec3
PLACEMENTS = {"1m_at_origin": (1.0, 0.0), "1mm_at_1km": (1e-3, 1e3), "1km_at_1km": (1e3, 1e3),
              "1mm_at_origin": (1e-3, 0.0)}
MIN_SINE = 0.3  # the angle between the edges: no slivers, which test nothing else
MIN_COSINE = 0.1  # incidences up to 84 degrees
N = 2000


@ti.kernel
def _quad_hits(q: ti.types.ndarray(dtype=vec3, ndim=2), frames: ti.types.ndarray(dtype=vec3, ndim=2),
               o: ti.types.ndarray(dtype=vec3, ndim=1), d: ti.types.ndarray(dtype=vec3, ndim=1),
               framed: ti.template(), out: ti.types.ndarray(dtype=ti.f32, ndim=2)):
    for i in range(o.shape[0]):
        hit, t, a, b = 0, 0.0, 0.0, 0.0
        if ti.static(framed):
            hit, t, a, b = isect.quad_framed(o[i], d[i], q[i, 0], frames[i, 0], frames[i, 1], frames[i, 2], INF)
        else:
            hit, t, a, b = isect.quad(o[i], d[i], q[i, 0], q[i, 1], q[i, 2], INF)
        out[i, 0] = hit
        out[i, 1] = t
        out[i, 2] = a
        out[i, 3] = b


def quad_hits(framed, q, o, d):
    """(hit, t, a, b) of ray i against quad i (corner, edge_u, edge_v), f32 as the renderer computes them."""
    out = np.zeros((len(o), 4), np.float32)
    q = np.ascontiguousarray(q, np.float32)
    _quad_hits(q, np.ascontiguousarray(isect.quad_frames(q)), np.ascontiguousarray(o, np.float32),
               np.ascontiguousarray(d, np.float32), framed, out)
    return out[:, 0] == 1, out[:, 1].astype(np.float64), out[:, 2].astype(np.float64), out[:, 3].astype(np.float64)


def random_quads(rng, n, scale, distance):
    """n f32 parallelograms (corner, edge_u, edge_v) with edges ~scale and sin(angle) >= MIN_SINE."""
    quads = np.zeros((0, 3, 3), np.float32)
    while len(quads) < n:
        corner = distance * unit(rng.normal(size=(n, 3))) + scale * rng.normal(size=(n, 3))
        eu, ev = scale * rng.normal(size=(n, 3)), scale * rng.normal(size=(n, 3))
        sine = np.linalg.norm(np.cross(eu, ev), axis=1) / (np.linalg.norm(eu, axis=1) * np.linalg.norm(ev, axis=1))
        q = np.stack([corner, eu, ev], axis=1).astype(np.float32)
        quads = np.concatenate([quads, q[sine >= MIN_SINE]])
    return quads[:n]


def shape(q):
    """Longest edge (a diagonal), conditioning L^2 / area and unit normal of quads, float64."""
    q = np.asarray(q, np.float64)
    cross = np.cross(q[:, 1], q[:, 2])
    area = np.linalg.norm(cross, axis=1)
    longest = np.maximum(np.linalg.norm(q[:, 1] + q[:, 2], axis=1), np.linalg.norm(q[:, 1] - q[:, 2], axis=1))
    return longest, longest ** 2 / area, cross / area[:, None]


def rays_at(rng, q, ab, side):
    """f32 rays towards the points corner + a edge_u + b edge_v of each quad, from `side` (+1: the
    side the normal faces), starting 0.5 to 3 quad sizes away."""
    longest, _, normal = shape(q)
    q64 = q.astype(np.float64)
    target = q64[:, 0] + ab[:, :1] * q64[:, 1] + ab[:, 1:] * q64[:, 2]
    towards = -side * tilted(rng, normal, MIN_COSINE)
    distance = longest * rng.uniform(0.5, 3.0, len(q))
    o = (target - distance[:, None] * towards).astype(np.float32)
    return o, unit(target - o.astype(np.float64)).astype(np.float32)


def quads_as_triangles(q):
    """The triangles (corner, corner + edge_u, corner + edge_v): their (t, b1, b2) of a ray are the
    quad's (t, a, b)."""
    q = np.asarray(q, np.float64)
    return np.stack([q[:, 0], q[:, 0] + q[:, 1], q[:, 0] + q[:, 2]], axis=1)


@pytest.mark.parametrize("framed", [True, False], ids=["framed", "plain"])
@pytest.mark.parametrize("side", [1, -1], ids=["front", "back"])
@pytest.mark.parametrize("placement", PLACEMENTS)
def test_quad_hits_from_both_sides(framed, side, placement):
    scale, distance = PLACEMENTS[placement]
    rng = np.random.default_rng(abs(hash((placement, side))) % 2**32)
    q = random_quads(rng, N, scale, distance)
    ab = rng.uniform(0.02, 0.98, (N, 2))
    o, d = rays_at(rng, q, ab, side)
    hit, t, a, b = quad_hits(framed, q, o, d)
    assert hit.all()
    t_exact, a_exact, b_exact = exact_triangle_hit(o, d, quads_as_triangles(q))
    longest, kappa, normal = shape(q)
    tol = triangle_tolerance(t_exact, longest, kappa, (d * normal).sum(axis=1))
    q64 = q.astype(np.float64)
    exact_point = o + t_exact[:, None] * d
    ray_point = o + t[:, None] * d
    quad_point = q64[:, 0] + a[:, None] * q64[:, 1] + b[:, None] * q64[:, 2]
    assert np.all(np.linalg.norm(ray_point - exact_point, axis=1) <= tol)
    assert np.all(np.linalg.norm(quad_point - exact_point, axis=1) <= tol)
    assert np.all(np.abs(a - a_exact) * longest <= tol) and np.all(np.abs(b - b_exact) * longest <= tol)


@pytest.mark.parametrize("placement", PLACEMENTS)
def test_rays_beside_a_quad_miss_and_both_forms_agree(placement):
    scale, distance = PLACEMENTS[placement]
    rng = np.random.default_rng(abs(hash(placement)) % 2**32)
    q = random_quads(rng, N, scale, distance)
    ab = rng.uniform(0.02, 0.98, (N, 2))
    beyond = rng.uniform(0.05, 0.5, N)
    which = rng.integers(0, 2, N)
    low = rng.integers(0, 2, N) == 1
    ab[np.arange(N), which] = np.where(low, -beyond, 1.0 + beyond)
    o, d = rays_at(rng, q, ab, rng.choice([-1, 1]))
    framed = quad_hits(True, q, o, d)[0]
    plain = quad_hits(False, q, o, d)[0]
    assert not framed.any() and not plain.any()
    inside = rng.uniform(0.02, 0.98, (N, 2))
    o, d = rays_at(rng, q, inside, 1)
    assert np.array_equal(quad_hits(True, q, o, d)[0], quad_hits(False, q, o, d)[0])

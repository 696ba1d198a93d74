"""Triangle hits are right from both sides: the point the barycentrics name is the point o + t d.

Distances alone missed a bug: for a ray meeting a triangle from behind (det < 0) the watertight
test flipped t and det but not the edge functions, so b1, b2 came out negated and every surface
rebuilt from them (point, shading normal, uv) sat at the wrong place. Every ray leaving a glass
mesh meets a back face. Here:

- both triangle tests (`triangle_watertight`, `triangle_moller_trumbore`), called through a tiny
  kernel, on random triangles of 1 mm, 1 m and 1 km, at the origin and 1 km away, hit from both
  sides at random incidences: b0, b1, b2 lie in [0, 1] and both b0 v0 + b1 v1 + b2 v2 and o + t d
  equal the exact intersection (float64) within the f32 bound of tests/geometry/hit_bounds.py;
- the exact case of the bug report;
- through MeshGeometry (a BVH over a closed mesh with per-vertex normals and uvs, both triangle
  tests): the same point seen from outside and from inside gives the same uv and shading normal,
  both equal to the exact interpolation there, surface().p equals o + t d, and front_face and
  n_geo say which side the ray came from.
"""
import numpy as np
import pytest
import taichi as ti
import trimesh

from renderer.geometry import intersect as isect
from renderer.geometry.interface import INF
from renderer.geometry.mesh_data import MeshData
from tests.geometry.hit_bounds import (U, exact_triangle_hit, interior_barycentrics, tilted, triangle_shape,
                                       triangle_tolerance, unit)
from tests.geometry.mesh_helpers import SurfaceProbe, geometry_from

vec3 = ti.math.vec3
TESTS = ("watertight", "moller")
# (edge scale, distance of the triangles from the origin), metres
PLACEMENTS = {"1m_at_origin": (1.0, 0.0), "1mm_at_1km": (1e-3, 1e3), "1km_at_1km": (1e3, 1e3),
              "1mm_at_origin": (1e-3, 0.0)}
MAX_KAPPA = 8.0  # no slivers: the bound grows with kappa, and slivers test nothing else
MIN_COSINE = 0.1  # incidences up to 84 degrees
# Every barycentric lies in [0, 1] up to the rounding of b0 = 1 - b1 - b2 from f32 b1, b2 (each
# a quotient rounded by u, over a det rounded by 2u): 4u.
BARY_SLACK = 4 * U


@ti.kernel
def _triangle_hits(v: ti.types.ndarray(dtype=vec3, ndim=2), o: ti.types.ndarray(dtype=vec3, ndim=1),
                   d: ti.types.ndarray(dtype=vec3, ndim=1), moller: ti.template(),
                   out: ti.types.ndarray(dtype=ti.f32, ndim=2)):
    for i in range(o.shape[0]):
        hit, t, b1, b2 = 0, 0.0, 0.0, 0.0
        if ti.static(moller):
            hit, t, b1, b2 = isect.triangle_moller_trumbore(o[i], d[i], v[i, 0], v[i, 1], v[i, 2], INF)
        else:
            k, s = isect.watertight_setup(d[i])
            hit, t, b1, b2 = isect.triangle_watertight(o[i], k, s, v[i, 0], v[i, 1], v[i, 2], INF)
        out[i, 0] = hit
        out[i, 1] = t
        out[i, 2] = b1
        out[i, 3] = b2


def triangle_hits(test, v, o, d):
    """(hit, t, b1, b2) of ray i against triangle i, f32 as the renderer computes them."""
    out = np.zeros((len(o), 4), np.float32)
    _triangle_hits(np.ascontiguousarray(v, np.float32), np.ascontiguousarray(o, np.float32),
                   np.ascontiguousarray(d, np.float32), test == "moller", out)
    return out[:, 0] == 1, out[:, 1].astype(np.float64), out[:, 2].astype(np.float64), out[:, 3].astype(np.float64)


def random_triangles(rng, n, scale, distance):
    """n f32 triangles of edges ~scale around random centres `distance` from the origin, with
    kappa <= MAX_KAPPA."""
    tris = np.zeros((0, 3, 3), np.float32)
    while len(tris) < n:
        centre = distance * unit(rng.normal(size=(n, 1, 3)))
        v = (centre + scale * rng.normal(size=(n, 3, 3))).astype(np.float32)
        _, kappa, _ = triangle_shape(v)
        tris = np.concatenate([tris, v[kappa <= MAX_KAPPA]])
    return tris[:n]


def rays_at(rng, v, normal, side):
    """f32 rays at a random interior point of each triangle (barycentrics >= 0.02) from `side`
    (+1: the side e1 x e2 points to, the front), at a random incidence with cos >= MIN_COSINE, from
    0.3 to 100 edge lengths away. Directions are computed from the rounded origins, so each f32
    ray passes within f32 rounding of its target."""
    n = len(v)
    longest, _, _ = triangle_shape(v)
    target = np.einsum("ni,nij->nj", interior_barycentrics(rng, n), v.astype(np.float64))
    w = tilted(rng, normal, MIN_COSINE)
    o = (target + (side * longest * 10.0 ** rng.uniform(-0.5, 2.0, n))[:, None] * w).astype(np.float32)
    d = unit(target - o).astype(np.float32)
    return o, d


def check_hits(test, v, o, d, context):
    """Every ray hits; barycentrics in [0, 1]; both hit points equal the exact one within TOL."""
    hit, t, b1, b2 = triangle_hits(test, v, o, d)
    assert hit.all(), f"{context}: {np.count_nonzero(~hit)} rays aimed inside their triangle missed"
    b0 = 1.0 - b1 - b2
    for name, b in (("b0", b0), ("b1", b1), ("b2", b2)):
        assert (b >= -BARY_SLACK).all() and (b <= 1.0 + BARY_SLACK).all(), (
            f"{context}: {name} outside [0, 1]: {b.min():.3g} .. {b.max():.3g}")
    vv = v.astype(np.float64)
    from_bary = b0[:, None] * vv[:, 0] + b1[:, None] * vv[:, 1] + b2[:, None] * vv[:, 2]
    along = o.astype(np.float64) + t[:, None] * d.astype(np.float64)
    t_exact, e1, e2 = exact_triangle_hit(o, d, v)
    exact = (1.0 - e1 - e2)[:, None] * vv[:, 0] + e1[:, None] * vv[:, 1] + e2[:, None] * vv[:, 2]
    longest, kappa, normal = triangle_shape(v)
    tol = triangle_tolerance(t_exact, longest, kappa, (normal * d).sum(axis=1))
    for name, p in (("b0 v0 + b1 v1 + b2 v2", from_bary), ("o + t d", along)):
        ratio = np.linalg.norm(p - exact, axis=1) / tol
        worst = int(np.argmax(ratio))
        assert ratio.max() <= 1.0, (f"{context}: {name} is {ratio.max():.3g} tolerances from the exact hit "
                                    f"(ray {worst}: {p[worst]} vs {exact[worst]})")
    return t, b1, b2


@pytest.mark.parametrize("placement", PLACEMENTS)
@pytest.mark.parametrize("test", TESTS)
def test_barycentric_point_is_the_hit_point_from_both_sides(test, placement):
    scale, distance = PLACEMENTS[placement]
    rng = np.random.default_rng(list(PLACEMENTS).index(placement) + 1)
    n = 2000
    v = random_triangles(rng, n, scale, distance)
    _, _, normal = triangle_shape(v)
    for side, name in ((1.0, "front"), (-1.0, "back")):
        o, d = rays_at(rng, v, normal, side)
        check_hits(test, v, o, d, f"{test} {placement} {name}")


@pytest.mark.parametrize("test", TESTS)
def test_reported_back_face_case(test):
    """The bug report: from (0.7, 0.3, -2) along +z through the triangle (0,0,0), (1,0,0), (0,1,0),
    whose normal e1 x e2 is +z, so the ray meets its back; the watertight test returned the
    point (-0.7, -0.3, 0). Both windings."""
    o = np.array([[0.7, 0.3, -2.0]], np.float32)
    d = np.array([[0.0, 0.0, 1.0]], np.float32)
    for v, side in ((np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], np.float32), "back"),
                    (np.array([[[0, 0, 0], [0, 1, 0], [1, 0, 0]]], np.float32), "front")):
        assert (triangle_shape(v)[2] @ d[0] > 0) == (side == "back")  # the side is the one named
        t, b1, b2 = check_hits(test, v, o, d, f"{test} {side}")
        point = (1.0 - b1 - b2) * v[0, 0] + b1 * v[0, 1] + b2 * v[0, 2]
        longest, kappa, _ = triangle_shape(v)
        tol = triangle_tolerance(2.0, longest, kappa, 1.0)[0]  # the bound check_hits applies
        assert abs(t[0] - 2.0) <= tol
        assert np.linalg.norm(point - [0.7, 0.3, 0.0]) <= tol, f"{test} {side}: the point is {point}"


# --- through MeshGeometry ----------------------------------------------------------------------

MESH_CENTRE = np.array([3.0, -2.0, 5.0])
MESH_RADIUS = 0.8
NORMAL_TILT = 0.35  # how far (radians, ~20 degrees) vertex normals lean away from the radial one


@pytest.fixture(scope="module")
def decorated_ball():
    """A closed icosphere (320 triangles) off the origin with per-vertex normals tilted at random
    and random per-vertex uvs: attributes that only a right barycentric interpolation reproduces."""
    rng = np.random.default_rng(7)
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=MESH_RADIUS)
    vertices = sphere.vertices + MESH_CENTRE
    radial = unit(sphere.vertices)
    normals = unit(radial + NORMAL_TILT * unit(np.cross(radial, rng.normal(size=radial.shape))))
    uvs = rng.uniform(0.0, 1.0, (len(vertices), 2))
    faces = np.asarray(sphere.faces)
    data = MeshData(tri_vertices=vertices[faces].astype(np.float32), tri_normals=normals[faces].astype(np.float32),
                    tri_uvs=uvs[faces].astype(np.float32), tri_material=np.zeros(len(faces), np.int32))
    return data


@pytest.mark.parametrize("test", TESTS)
def test_back_face_shades_like_the_front(decorated_ball, test):
    """The same point of each triangle from outside (front face) and from inside (back face),
    along one line at cos >= 0.5: same prim, uv and shading normal, each equal to the exact
    interpolation at the exact hit; surface().p = o + t d.

    Tolerances: a point error dP on the triangle moves the barycentrics by at most
    |dP| / sigma_min(E) (E = [e1 e2]) and so an attribute a by |A| |dP| / sigma_min(E), A its
    matrix of differences [a1 - a0, a2 - a0]; dP is bounded by TOL (hit_bounds) plus the f32
    evaluation of the interpolations (5 roundings of at most max|v|, max|a|); a normalised normal
    moves by at most 2 |d interp| / |interp|."""
    data = decorated_ball
    probe = SurfaceProbe(geometry_from(data, triangle_test=test))
    rng = np.random.default_rng(8)
    v = data.tri_vertices.astype(np.float64)
    n_tri = len(v)
    prim = np.arange(n_tri)
    x = np.einsum("ni,nij->nj", interior_barycentrics(rng, n_tri), v)
    longest, kappa, normal = triangle_shape(data.tri_vertices)
    w = tilted(rng, normal, 0.5)
    reach = 0.3 * MESH_RADIUS  # inside the ball: chords at cos >= 0.5 are longer than the radius
    views = {}
    for side, name in ((1.0, "outside"), (-1.0, "inside")):
        o = (x + side * reach * w).astype(np.float32)
        d = unit(x - o).astype(np.float32)
        out = probe.shoot(o, d)
        assert (out[:, SurfaceProbe.HIT] == 1).all(), f"{test} {name}: a ray aimed at a triangle missed"
        assert np.array_equal(out[:, SurfaceProbe.PRIM].astype(int), prim), f"{test} {name}: another triangle hit"
        assert (out[:, SurfaceProbe.FRONT] == (1 if side > 0 else 0)).all(), f"{test} {name}: front_face wrong"
        assert ((out[:, SurfaceProbe.N_GEO] * normal).sum(axis=1) > 0.0).all(), f"{test} {name}: n_geo points in"
        t_exact, e1, e2 = exact_triangle_hit(o, d, data.tri_vertices)
        bary = np.stack([1.0 - e1 - e2, e1, e2], axis=1)
        cos_d = (normal * d).sum(axis=1)
        point_tol = triangle_tolerance(t_exact, longest, kappa, cos_d) + 5 * U * np.abs(v).max(axis=(1, 2))
        p = out[:, SurfaceProbe.P].astype(np.float64)
        along = o + out[:, SurfaceProbe.T, None].astype(np.float64) * d
        assert (np.linalg.norm(p - along, axis=1) <= 2 * point_tol).all(), f"{test} {name}: surface().p is not o + t d"
        assert (np.linalg.norm(p - np.einsum("ni,nij->nj", bary, v), axis=1) <= point_tol).all()
        sigma = np.linalg.svd(np.stack([v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]], axis=2), compute_uv=False)[:, -1]

        def attribute_tol(a):
            diffs = np.stack([a[:, 1] - a[:, 0], a[:, 2] - a[:, 0]], axis=2)
            return np.linalg.norm(diffs, ord=2, axis=(1, 2)) * point_tol / sigma + 5 * U * np.abs(a).max(axis=(1, 2))

        uv_exact = np.einsum("ni,nij->nj", bary, data.tri_uvs.astype(np.float64))
        interp = np.einsum("ni,nij->nj", bary, data.tri_normals.astype(np.float64))
        ns_exact = unit(interp)
        # The renderer bends a shading normal that faces away from the viewer (shading.py); these
        # views are far from that, so the interpolation is all there is to compare.
        assert (np.abs((ns_exact * d).sum(axis=1)) > 0.05).all()
        uv = out[:, SurfaceProbe.UV].astype(np.float64)
        ns = out[:, SurfaceProbe.N_SHADING].astype(np.float64)
        uv_error = np.abs(uv - uv_exact).max(axis=1)
        assert (uv_error <= attribute_tol(data.tri_uvs)).all(), f"{test} {name}: uv off by up to {uv_error.max():.3g}"
        ns_tol = 2 * attribute_tol(data.tri_normals) / np.linalg.norm(interp, axis=1) + 4 * U
        ns_error = np.linalg.norm(ns - ns_exact, axis=1)
        assert (ns_error <= ns_tol).all(), f"{test} {name}: shading normal off by up to {ns_error.max():.3g}"
        views[name] = (uv, ns, attribute_tol(data.tri_uvs), ns_tol)
    # and so the two sides agree with each other, within the sum of their tolerances
    (uv_out, ns_out, uv_tol_out, ns_tol_out), (uv_in, ns_in, uv_tol_in, ns_tol_in) = views.values()
    assert (np.abs(uv_out - uv_in).max(axis=1) <= uv_tol_out + uv_tol_in).all()
    assert (np.linalg.norm(ns_out - ns_in, axis=1) <= ns_tol_out + ns_tol_in).all()

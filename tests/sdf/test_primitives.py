"""The SDF distance functions: exact against numpy references, closest-point property, Lipschitz 1.

Sphere tracing is only safe if every distance is a lower bound on the distance to the surface and
varies no faster than the point (Lipschitz 1). The primitives are documented as exact Euclidean
distances, so they are compared with references written from the geometric definitions
(sdf_helpers.REFERENCE) and, for the cone and torus, with a dense sampling of the surface.

Float tolerances: the kernels run in f32 (24-bit mantissa, unit roundoff 6e-8). With |p| <= 3 one
rounding is <= 2e-7, and a distance takes a dozen operations, so TOL = 2e-6 (absolute, scaled with
|p| and the transform scale where those are larger) bounds the evaluation error with a margin.
"""
import numpy as np
import pytest
from scipy.spatial import cKDTree

from renderer.scene.description import MaterialSpec
from sdf_helpers import (
    PRIMITIVE_PARAMS,
    PRIMITIVES,
    make_geometry,
    node,
    random_directions,
    ref_node,
    ref_scene,
    sdf,
    sdf_material,
)

TOL = 2e-6  # absolute f32 error of one distance evaluation at |p| <= 3 (see the module docstring)

# Parameter sets per primitive: the tests' defaults plus degenerate-looking but valid shapes.
PARAMETER_SETS = {
    "sphere": [{}, {"radius": 0.05}],
    "box": [{}, {"size": (0.01, 1.0, 2.0)}],
    "rounded_box": [{}, {"size": (0.6, 0.6, 0.6), "radius": 0.3}, {"size": (2.0, 0.3, 1.0), "radius": 0.01}],
    "torus": [{}, {"major_radius": 1.0, "minor_radius": 0.9}, {"major_radius": 0.8, "minor_radius": 0.02}],
    "capsule": [{}, {"height": 0.01, "radius": 0.5}, {"height": 2.0, "radius": 0.05}],
    "cylinder": [{}, {"height": 0.05, "radius": 1.0}, {"height": 2.0, "radius": 0.05}],
    "cone": [{}, {"height": 0.2, "radius": 1.0}, {"height": 2.0, "radius": 0.1}],
    "plane": [{}, {"normal": (1.0, 2.0, -0.5), "offset": 0.7}, {"normal": (0.0, 0.0, -1.0), "offset": -1.3}],
}
PARAM_CASES = [pytest.param(k, i, id=f"{k}-{i}") for k in PRIMITIVES for i in range(len(PARAMETER_SETS[k]))]


def _extent(kind, params):
    """Half side of a centred cube holding the primitive with these parameters."""
    p = {**PRIMITIVE_PARAMS[kind], **params}
    if kind == "sphere":
        return p["radius"]
    if kind in ("box", "rounded_box"):
        return 0.5 * max(p["size"])
    if kind == "torus":
        return p["major_radius"] + p["minor_radius"]
    if kind == "capsule":
        return 0.5 * p["height"] + p["radius"]
    if kind in ("cylinder", "cone"):
        return max(0.5 * p["height"], p["radius"])
    return 1.0 + abs(p.get("offset", 0.0))


def _numeric_gradient(objects, p, h=1e-6):
    g = np.zeros_like(p)
    for axis in range(3):
        e = np.zeros(3)
        e[axis] = h
        g[:, axis] = (ref_scene(objects, p + e) - ref_scene(objects, p - e)) / (2 * h)
    return g


def _sample_points(rng, objects, extent, count=20000, box=None):
    """Uniform points around the objects, plus as many pulled onto their surface (Newton step on the
    reference distance) with offsets of 1% of the extent, so both sides and the surface are covered."""
    box = 1.5 * extent + 0.2 if box is None else box
    uniform = rng.uniform(-box, box, (count, 3))
    seeds = rng.uniform(-box, box, (count, 3))
    d = ref_scene(objects, seeds)
    h = 1e-6 * max(1.0, extent)
    g = _numeric_gradient(objects, seeds, h)
    g /= np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-12)
    near = seeds - d[:, None] * g + rng.normal(scale=0.01 * extent, size=seeds.shape)
    return np.concatenate([uniform, near])


@pytest.mark.parametrize("kind,case", PARAM_CASES)
def test_primitive_matches_reference(kind, case):
    """Each primitive's Taichi distance equals the numpy reference, inside and outside."""
    rng = np.random.default_rng(1000 + PRIMITIVES.index(kind) * 10 + case)
    n = node(kind, **PARAMETER_SETS[kind][case])
    p = _sample_points(rng, (n,), _extent(kind, PARAMETER_SETS[kind][case]), count=10000)
    p = p.astype(np.float32).astype(np.float64)  # the points the kernel sees
    got = sdf(make_geometry(n), p)
    want = ref_node(n, p)
    inside = want < 0
    assert inside.sum() > 200 and (~inside).sum() > 200, "sampling must cover both sides"
    err = np.abs(got - want)
    tol = TOL * np.maximum(1.0, np.linalg.norm(p, axis=1))
    worst = int(np.argmax(err / tol))
    assert np.all(err <= tol), f"{kind}{PARAMETER_SETS[kind][case]}: at {p[worst]} got {got[worst]}, want {want[worst]}"


# --- closest-point property: |d(p)| is the distance to the nearest surface point ---------------


def _cone_surface(height, radius, n_angle, n_along):
    """Lateral surface and base disc of the cone, on grids; returns (points, sampling radius)."""
    h = 0.5 * height
    u = np.linspace(0.0, 2 * np.pi, n_angle, endpoint=False)
    s = np.linspace(0.0, 1.0, n_along)
    uu, ss = np.meshgrid(u, s, indexing="ij")
    rho = radius * (1.0 - ss)
    lateral = np.stack([rho * np.cos(uu), -h + 2 * h * ss, rho * np.sin(uu)], -1).reshape(-1, 3)
    rings = np.linspace(0.0, radius, n_along)
    uu, rr = np.meshgrid(u, rings, indexing="ij")
    base = np.stack([rr * np.cos(uu), np.full_like(rr, -h), rr * np.sin(uu)], -1).reshape(-1, 3)
    # Every surface point lies in a grid cell whose sides are at most the arc at the base radius
    # and the step along the slant (or radius); the nearest sample is within half its diagonal.
    du = radius * 2 * np.pi / n_angle
    dv = max(np.hypot(radius, height), radius) / (n_along - 1)
    return np.concatenate([lateral, base]), 0.5 * np.hypot(du, dv)


def _torus_surface(major, minor, n_angle, n_tube):
    u = np.linspace(0.0, 2 * np.pi, n_angle, endpoint=False)
    v = np.linspace(0.0, 2 * np.pi, n_tube, endpoint=False)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    ring = major + minor * np.cos(vv)
    pts = np.stack([ring * np.cos(uu), minor * np.sin(vv), ring * np.sin(uu)], -1).reshape(-1, 3)
    du = (major + minor) * 2 * np.pi / n_angle
    dv = minor * 2 * np.pi / n_tube
    return pts, 0.5 * np.hypot(du, dv)


def _cylinder_surface(height, radius, n_angle, n_along):
    h = 0.5 * height
    u = np.linspace(0.0, 2 * np.pi, n_angle, endpoint=False)
    y = np.linspace(-h, h, n_along)
    uu, yy = np.meshgrid(u, y, indexing="ij")
    side = np.stack([radius * np.cos(uu), yy, radius * np.sin(uu)], -1).reshape(-1, 3)
    rings = np.linspace(0.0, radius, n_along)
    uu, rr = np.meshgrid(u, rings, indexing="ij")
    caps = [np.stack([rr * np.cos(uu), np.full_like(rr, sy * h), rr * np.sin(uu)], -1).reshape(-1, 3)
            for sy in (-1.0, 1.0)]
    du = radius * 2 * np.pi / n_angle
    dv = max(height, radius) / (n_along - 1)
    return np.concatenate([side] + caps), 0.5 * np.hypot(du, dv)


SURFACES = {
    "cone": [({"height": 1.0, "radius": 0.5}, lambda p: _cone_surface(p["height"], p["radius"], 720, 300)),
             ({"height": 0.2, "radius": 1.0}, lambda p: _cone_surface(p["height"], p["radius"], 1024, 300))],
    "torus": [({"major_radius": 0.5, "minor_radius": 0.15},
               lambda p: _torus_surface(p["major_radius"], p["minor_radius"], 1024, 256))],
    "cylinder": [({"height": 0.9, "radius": 0.4}, lambda p: _cylinder_surface(p["height"], p["radius"], 1024, 300))],
}


@pytest.mark.parametrize("kind,index", [(k, i) for k in SURFACES for i in range(len(SURFACES[k]))])
def test_closest_point_property(kind, index):
    """|d(p)| equals the distance to a dense sampling of the surface, to within its resolution.

    Samples lie on the surface, so the sampled distance can only exceed the true one, and by at
    most the sampling radius r (half the diagonal of a grid cell): 0 <= sampled - |d| <= r.
    """
    params, surface = SURFACES[kind][index]
    pts, resolution = surface(params)
    n = node(kind, **params)
    rng = np.random.default_rng(2000 + index)
    extent = _extent(kind, params)
    p = _sample_points(rng, (n,), extent, count=4000).astype(np.float32).astype(np.float64)
    d = sdf(make_geometry(n), p)
    sampled, _ = cKDTree(pts).query(p)
    excess = sampled - np.abs(d)
    assert (d < 0).sum() > 100
    assert excess.min() >= -TOL, f"{kind}: |d| exceeds the distance to a surface sample by {-excess.min():.2e}"
    assert excess.max() <= resolution + TOL, f"{kind}: surface {excess.max():.2e} farther than |d| (r={resolution:.2e})"
    # The bound is not vacuous: the uniform half of the points lies mostly far beyond it.
    assert np.mean(np.abs(d) > 10 * resolution) > 0.4


# --- Lipschitz 1, for every primitive, operator and transform ---------------------------------


def _prim_cases():
    return [pytest.param((node(k),), id=k) for k in PRIMITIVES]


def _operator_cases():
    box = node("box", size=(1.0, 0.8, 0.6))
    ball = node("sphere", radius=0.55, translate=(0.3, 0.2, 0.1))
    cases = {
        "union": node("union", box, ball, node("torus", translate=(0.0, -0.5, 0.0))),
        "intersection": node("intersection", box, ball),
        "subtraction": node("subtraction", box, ball, node("cylinder", height=2.0, radius=0.1)),
        "smooth_union": node("smooth_union", node("cylinder", height=1.2, radius=0.25, translate=(0, 0.6, 0)),
                             node("sphere", radius=0.35, translate=(0, 1.3, 0)), k=0.25),
        "smooth_union_wide": node("smooth_union", box, ball, node("capsule", rotate=(0, 0, 90)), k=0.8),
        "repeat_finite": node("repeat", node("sphere", radius=0.3), period=(1.0, 0.0, 1.5), limit=(2, 0, 1)),
        "repeat_infinite": node("repeat", node("box", size=(0.5, 0.3, 0.7)), period=(1.0, 1.0, 1.0)),
        "repeat_of_union": node("repeat", node("union", node("sphere", radius=0.2),
                                                node("box", size=(0.1, 0.6, 0.1))), period=(0.8, 0.8, 0.0)),
        "nested": node("subtraction", node("smooth_union", box, ball, k=0.3),
                       node("repeat", node("sphere", radius=0.12), period=(0.3, 0.3, 0.3), limit=(1, 1, 1))),
    }
    return [pytest.param((v,), id=k) for k, v in cases.items()]


def _transform_cases():
    t = dict(translate=(0.3, -0.2, 0.5))
    r = dict(rotate=(30.0, 45.0, 60.0))
    cases = {
        "translate": (node("box", **t),),
        "rotate": (node("cone", **r),),
        "scale_0.3": (node("torus", scale=0.3),),
        "scale_2.5": (node("rounded_box", scale=2.5),),
        "scale_0.01": (node("capsule", scale=0.01),),
        "scale_100": (node("cylinder", scale=100.0),),
        "all_batched": (node("cone", scale=1.7, **t, **r), node("cone", scale=0.4, translate=(-1, 0, 0))),
        "all_compound": (node("union", node("box", rotate=(10, 0, 0)), node("sphere", translate=(1, 0, 0), scale=0.5),
                              scale=1.7, **t, **r),),
        "nested_scales": (node("repeat", node("torus", scale=0.5, rotate=(90, 0, 0)), period=(1.0, 0.0, 0.0),
                               limit=(3, 0, 0), scale=0.2, rotate=(0, 0, 30)),),
    }
    return [pytest.param(v, id=k) for k, v in cases.items()]


def _world_extent(objects):
    """A radius around the origin that holds the objects with room around them."""
    far = 0.0
    for o in objects:
        s = o.transform.scale
        far = max(far, np.linalg.norm(o.transform.translate) + 2.0 * s)
    return far


@pytest.mark.parametrize("objects", _prim_cases() + _operator_cases() + _transform_cases())
def test_lipschitz(objects):
    """|d(p) - d(q)| <= |p - q| for random pairs from 1e-3 to several metres apart (scaled with the
    objects), and the exact reference agrees with the renderer on these trees."""
    rng = np.random.default_rng(3000)
    geo = make_geometry(*objects)
    extent = _world_extent(objects)
    p = _sample_points(rng, objects, extent, count=10000, box=extent)
    n = len(p)
    sep = extent * 10.0 ** rng.uniform(-3.5, 0.5, n)
    q = p + random_directions(rng, n) * sep[:, None]
    p32 = p.astype(np.float32)
    q32 = q.astype(np.float32)
    dp = sdf(geo, p32).astype(np.float64)
    dq = sdf(geo, q32).astype(np.float64)
    dist = np.linalg.norm(p32.astype(np.float64) - q32.astype(np.float64), axis=1)
    magnitude = np.maximum.reduce([np.abs(dp), np.abs(dq), np.linalg.norm(p, axis=1), np.linalg.norm(q, axis=1),
                                   np.ones(n)])
    tol = 2 * TOL * magnitude  # two f32 evaluations, each accurate to TOL relative to its magnitude
    excess = np.abs(dp - dq) - dist - tol
    worst = int(np.argmax(excess))
    assert excess.max() <= 0.0, (f"|d(p)-d(q)| = {abs(dp[worst] - dq[worst]):.6g} > |p-q| = {dist[worst]:.6g} "
                                 f"at p={p[worst]}, q={q[worst]}")
    # The pairs probe the surface region, not only empty space.
    assert (np.sign(dp) != np.sign(dq)).sum() > 100


@pytest.mark.parametrize("objects", _operator_cases() + _transform_cases())
def test_trees_match_reference(objects):
    """Operators and transforms compose as documented: the tree's distance equals a numpy evaluation
    (min, max, max(a, -b), polynomial smooth minimum, repetition as the minimum over explicit copies,
    transforms world = R (s q) + t with R = Rz Ry Rx) at random points."""
    rng = np.random.default_rng(4000)
    geo = make_geometry(*objects)
    extent = _world_extent(objects)
    p = _sample_points(rng, objects, extent, count=10000, box=extent).astype(np.float32).astype(np.float64)
    got = sdf(geo, p)
    want = np.min([ref_node(o, p) for o in objects], axis=0)
    tol = TOL * np.maximum.reduce([np.ones(len(p)), np.linalg.norm(p, axis=1), np.abs(want)])
    worst = int(np.argmax(np.abs(got - want) / tol))
    assert np.all(np.abs(got - want) <= tol), f"at {p[worst]}: got {got[worst]}, want {want[worst]}"


def test_smooth_union_bounds():
    """The polynomial smooth minimum lies in [min - k/4, min] and equals min once |a - b| >= k."""
    a = node("sphere", radius=0.5, translate=(-0.35, 0, 0))
    b = node("box", size=(0.6, 0.6, 0.6), translate=(0.35, 0, 0))
    k = 0.3
    geo = make_geometry(node("smooth_union", a, b, k=k))
    rng = np.random.default_rng(5)
    p = rng.uniform(-1.2, 1.2, (20000, 3)).astype(np.float32).astype(np.float64)
    got = sdf(geo, p)
    da, db = ref_node(a, p), ref_node(b, p)
    hard = np.minimum(da, db)
    assert np.all(got <= hard + TOL)
    assert np.all(got >= hard - k / 4 - TOL)
    far = np.abs(da - db) >= k
    assert np.allclose(got[far], hard[far], atol=TOL)
    assert (~far).sum() > 1000 and (got[~far] < hard[~far] - 1e-3).any()  # the blend is really there


def test_top_level_objects_batched_by_kind():
    """Top-level primitives are evaluated in per-kind loops over table ranges, in an order that
    differs from the file's; with kinds interleaved the scene distance is still the minimum over
    all objects and the material is that of the nearest one."""
    mats = tuple(MaterialSpec(name) for name in ("a", "b", "c"))
    objects = (
        node("sphere", translate=(-2, 0, 0), material="a"),
        node("box", translate=(0, 0, 0), rotate=(10, 20, 30), material="b"),
        node("sphere", radius=0.3, translate=(2, 0, 0), material="c"),
        node("union", node("torus"), node("capsule", translate=(0, 0.5, 0)), translate=(0, 2, 0), material="a"),
        node("cone", translate=(0, 0, 2), scale=1.5, material="b"),
        node("sphere", radius=0.4, translate=(0, 0, -2), material="b"),
        node("plane", offset=-1.5, material="c"),
    )
    geo = make_geometry(*objects, materials=mats)
    rng = np.random.default_rng(6)
    p = rng.uniform(-3, 3, (20000, 3)).astype(np.float32).astype(np.float64)
    d, material = sdf_material(geo, p)
    each = np.stack([ref_node(o, p) for o in objects])
    want = each.min(axis=0)
    assert np.allclose(d, want, atol=TOL * 4)
    assert np.allclose(sdf(geo, p), d)
    second = np.sort(each, axis=0)[1]
    clear = second - want > 1e-4  # no near-tie between two objects
    nearest = np.argmin(each, axis=0)
    want_material = np.array([[m.name for m in mats].index(o.material) for o in objects])[nearest]
    assert np.all(material[clear] == want_material[clear])
    assert len(np.unique(nearest[clear])) == len(objects)

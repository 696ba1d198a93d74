"""Sphere tracing: a traced ray never crosses a surface before its hit, whatever the over-relaxation.

For every primitive and operator, a thin plate and a transformed torus at scales 0.01, 0.7 and 100,
thousands of random rays start outside and inside the solids and are traced with omega = 1.6 and
omega = 1.0. For each ray the SDF is then sampled along the segment the marcher claims is free of
surfaces ([0, t - 2 threshold] for a hit, [0, t_max] for a miss by distance) and must keep the sign
it has at the origin.

How densely: the coarse samples are spaced at half the scene's smallest feature (so a feature of
that size cannot fall between two samples), and every interval whose end distances a, b satisfy
a + b <= spacing (the only intervals in which a Lipschitz-1 SDF leaves room for a surface) is
resampled at `fine` = max(hit threshold, 1e-3 x smallest feature). Hence any solid the ray crosses
with a chord longer than `fine` is detected, however thin the solid (sdf_helpers.first_crossing).
"""
import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.scene.description import MarchSettings
from renderer.scene.toml_loader import load_scene
from sdf_helpers import (
    first_crossing,
    intersect,
    make_geometry,
    node,
    normals,
    random_directions,
    ref_scene,
    sdf,
    trace,
)
from shaders_sdf.geometry import SdfGeometry

REPO = Path(__file__).resolve().parents[2]
THRESHOLD = 1e-4  # MarchSettings.min_threshold; rays here have no cone, so it is the hit threshold
MAX_STEPS = 256
OMEGAS = (3.0, 1.6, 1.0)  # 3.0: the default cap of adaptive marching (steps past 2 bounds on receding rays)
N_OUTSIDE = 2000
N_INSIDE = 1000


@dataclass(frozen=True)
class Spec:
    objects: tuple
    center: tuple  # centre of the cube the ray origins are drawn from
    extent: float  # half side of that cube (the solids fit in about 0.8 of it)
    feature: float  # smallest feature size (thickness, gap, tube diameter), metres
    smooth: bool  # C1 surface: no edges, corners or creases


def _torus_at(scale):
    t = (0.3 * scale, -0.2 * scale, 0.1 * scale)
    return Spec((node("torus", rotate=(70, 0, 20), translate=t, scale=scale),), t, 0.9 * scale, 0.3 * scale, True)


SCENES = {
    "sphere": Spec((node("sphere"),), (0, 0, 0), 1.0, 1.2, True),
    "box": Spec((node("box"),), (0, 0, 0), 0.9, 0.5, False),
    "rounded_box": Spec((node("rounded_box"),), (0, 0, 0), 0.8, 0.3, True),
    "torus": Spec((node("torus"),), (0, 0, 0), 0.9, 0.3, True),
    "capsule": Spec((node("capsule"),), (0, 0, 0), 0.9, 0.5, True),
    "cylinder": Spec((node("cylinder"),), (0, 0, 0), 0.8, 0.8, False),
    "cone": Spec((node("cone"),), (0, 0, 0), 0.8, 0.1, False),  # the apex region is as thin as we look
    "plane": Spec((node("plane", normal=(0.2, 1.0, -0.1), offset=0.1),), (0, 0, 0), 1.0, 1.0, True),
    "thin_plate": Spec((node("box", size=(1.2, 0.002, 0.8), rotate=(0, 0, 8)),), (0, 0, 0), 0.9, 0.002, False),
    "union": Spec((node("union", node("box", size=(1.0, 0.5, 0.6)), node("sphere", radius=0.4, translate=(0.4, 0.3, 0)),
                        node("torus", major_radius=0.4, minor_radius=0.08, translate=(-0.3, -0.3, 0.1))),),
                  (0, 0, 0), 1.0, 0.16, False),
    "intersection": Spec((node("intersection", node("box", size=(1.0, 1.0, 1.0)), node("sphere", radius=0.65)),),
                         (0, 0, 0), 0.9, 0.3, False),
    "subtraction": Spec((node("subtraction", node("box", size=(0.9, 0.9, 0.9)), node("sphere", radius=0.6)),),
                        (0, 0, 0), 0.9, 0.05, False),  # the corners left are thin shells
    "smooth_union": Spec((node("smooth_union", node("cylinder", height=1.2, radius=0.25, translate=(0, 0.6, 0)),
                               node("sphere", radius=0.35, translate=(0, 1.3, 0)), k=0.25),),
                         (0, 0.8, 0), 1.0, 0.5, False),
    "repeat_finite": Spec((node("repeat", node("sphere", radius=0.15), period=(0.5, 0.0, 0.5), limit=(2, 0, 2)),),
                          (0, 0, 0), 1.4, 0.2, True),
    "repeat_infinite": Spec((node("repeat", node("torus", major_radius=0.2, minor_radius=0.05, rotate=(90, 0, 0)),
                                  period=(0.8, 0.8, 0.8)),), (0, 0, 0), 1.2, 0.1, True),
    "transformed": _torus_at(0.7),
    "scale_0.01": _torus_at(0.01),
    "scale_100": _torus_at(100.0),
}
SCENE_IDS = list(SCENES)
CASES = [pytest.param(name, omega, id=f"{name}-w{omega}") for name in SCENE_IDS for omega in OMEGAS]


def _march(spec: Spec, omega: float) -> MarchSettings:
    return MarchSettings(min_threshold=THRESHOLD, max_steps=MAX_STEPS, max_distance=40.0 * spec.extent,
                         over_relaxation=omega)


@functools.lru_cache(maxsize=None)
def geometry(name: str) -> SdfGeometry:
    spec = SCENES[name]
    return make_geometry(*spec.objects)


def _origins(spec: Spec, rng):
    """N_OUTSIDE points outside the solids and N_INSIDE inside (by the numpy reference)."""
    c = np.asarray(spec.center, np.float64)
    # Away from the surfaces by more than the hit threshold: an origin closer than that is itself a
    # hit at t = 0, where the ray's direction decides nothing.
    margin = max(1e-3 * spec.feature, 3.0 * THRESHOLD)
    outside = []
    inside = []
    for _ in range(50):
        cand = c + rng.uniform(-spec.extent, spec.extent, (20000, 3))
        d = ref_scene(spec.objects, cand)
        outside.append(cand[d > margin])
        inside.append(cand[d < -margin])
        # Points pulled to the surface (Newton step on the reference) and pushed in by up to half the
        # smallest feature: thin solids get inside origins too.
        h = 1e-6 * spec.extent
        g = np.stack([(ref_scene(spec.objects, cand + e) - d) / h for e in np.eye(3) * h], axis=1)
        g /= np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-12)
        depth = rng.uniform(0.02, 0.5, len(cand)) * spec.feature
        pushed = cand - (d + depth)[:, None] * g
        inside.append(pushed[ref_scene(spec.objects, pushed) < -margin])
        if sum(map(len, outside)) >= N_OUTSIDE and sum(map(len, inside)) >= N_INSIDE:
            break
    return np.concatenate(outside)[:N_OUTSIDE], np.concatenate(inside)[:N_INSIDE]


@dataclass
class Run:
    spec: Spec
    omega: float
    t_max: float
    primary: object  # TraceResult
    inside: np.ndarray  # the origin is inside a solid (Taichi SDF < 0)
    refl: object  # TraceResult of the spawned mirror rays (hits only)
    refl_from: np.ndarray  # index of the primary ray each spawned mirror ray comes from
    trans: object
    trans_from: np.ndarray


@functools.lru_cache(maxsize=None)
def run(name: str, omega: float) -> Run:
    spec = SCENES[name]
    geo = geometry(name)
    geo.set_march(_march(spec, omega))
    rng = np.random.default_rng(SCENE_IDS.index(name))
    outside, inside = _origins(spec, rng)
    o = np.concatenate([outside, inside])
    d = random_directions(rng, len(o))
    # Half the outside rays aim at a point near the centre, so that most of them hit something.
    k = len(outside) // 2
    aim = np.asarray(spec.center) + rng.uniform(-0.6, 0.6, (k, 3)) * spec.extent - outside[:k]
    d[:k] = aim / np.linalg.norm(aim, axis=1, keepdims=True)
    t_max = 6.0 * spec.extent
    r = trace(geo, o, d, t_max)
    hit = r.hit == 1
    refl_from = np.flatnonzero(hit)
    trans_from = np.flatnonzero(hit & (r.trans_valid == 1))
    refl = trace(geo, r.refl_o[refl_from], r.refl_d[refl_from], t_max)
    trans = trace(geo, r.trans_o[trans_from], r.trans_d[trans_from], t_max)
    return Run(spec, omega, t_max, r, sdf(geo, r.o) < 0, refl, refl_from, trans, trans_from)


def _free_length(r):
    """The part of each ray the marcher claims is free of surfaces; 0 where it ran out of steps."""
    hit = r.hit == 1
    exhausted = ~hit & (r.work >= MAX_STEPS)
    return np.where(hit, np.maximum(r.t - 2.0 * r.eps, 0.0), np.where(exhausted, 0.0, r.t)), exhausted


def _check_no_crossing(name, r, what):
    spec = SCENES[name]
    length, exhausted = _free_length(r)
    coarse = int(min(20000, math.ceil(r.t_max / (0.5 * spec.feature))))
    fine = max(THRESHOLD, 1e-3 * spec.feature)
    crossing, _, _ = first_crossing(geometry(name), r.o, r.d, length, coarse, fine)
    bad = np.flatnonzero(crossing >= 0)
    assert bad.size == 0, (f"{name} {what}: {bad.size} rays cross a surface before their reported "
                           f"{'hit' if r.hit[bad[0]] else 'miss'}: o={r.o[bad[0]]}, d={r.d[bad[0]]}, "
                           f"t={r.t[bad[0]]}, crossing at s={crossing[bad[0]]}")
    # Rays that run out of steps report a miss short of t_max; they must stay rare here.
    assert exhausted.mean() < 0.01, f"{name} {what}: {exhausted.sum()} rays ran out of steps"


@pytest.mark.parametrize("name,omega", CASES)
def test_primary_rays_hit_the_first_surface(name, omega):
    """From outside and from inside: no sign change of the SDF before the hit (or before t_max on a
    miss by distance), so nothing was tunnelled through."""
    result = run(name, omega)
    r = result.primary
    assert (~result.inside).sum() >= N_OUTSIDE and result.inside.sum() >= N_INSIDE * 0.9
    hit = r.hit == 1
    assert hit[~result.inside].mean() > 0.2 and hit[result.inside].mean() > 0.2, "too few hits to test"
    _check_no_crossing(name, r, "primary rays")


@pytest.mark.parametrize("name,omega", CASES)
def test_hit_point_and_normal(name, omega):
    """At a hit |sdf| is below the hit threshold, n_geo and n_shading are unit vectors, an outside
    ray meets a front face and an inside ray a back face (its normal faces along the ray)."""
    result = run(name, omega)
    r = result.primary
    geo = geometry(name)
    hit = r.hit == 1
    d_hit = sdf(geo, r.p[hit])
    assert np.all(np.abs(d_hit) < r.eps[hit])
    assert np.allclose(r.eps[hit], THRESHOLD)
    for n in (r.n[hit], r.n_shading[hit]):
        assert np.all(np.isfinite(n))
        assert np.abs(np.linalg.norm(n, axis=1) - 1.0).max() < 1e-5
    front = r.front_face[hit] == 1
    from_inside = result.inside[hit]
    assert np.all(front[~from_inside]), "an outside ray hit a back face"
    assert not np.any(front[from_inside]), "an inside ray hit a front face"
    # The normal faces the side the ray came from, even at silhouettes where the march stops just
    # past the tangent point (surface() tilts it by at most what that takes).
    facing = np.einsum("ij,ij->i", r.d[hit], r.n[hit])
    assert np.all(facing[~from_inside] < 0.0) and np.all(facing[from_inside] > 0.0)


@pytest.mark.parametrize("name,omega", CASES)
def test_spawned_rays_hit_the_first_surface(name, omega):
    """Mirror and refracted rays spawned at the hits start on the side they leave to and are traced
    without crossing a surface, like primary rays (from whichever side they actually start)."""
    result = run(name, omega)
    geo = geometry(name)
    p = result.primary
    for what, spawned, src in (("reflected", result.refl, result.refl_from),
                               ("transmitted", result.trans, result.trans_from)):
        assert len(spawned) > 100
        # Which side the spawned ray leaves to: along n_geo (outside) or against it (inside).
        leaving_out = np.einsum("ij,ij->i", spawned.d, p.n[src]) > 0
        d0 = sdf(geo, spawned.o)
        wrong = (d0 > 0) != leaving_out
        if not result.spec.smooth:
            # At a convex edge a ray spawned *into* the solid can start outside it
            # (test_spawn_at_convex_edges); rays leaving to the outside are checked everywhere.
            wrong &= leaving_out
        wrong = np.flatnonzero(wrong)
        assert wrong.size == 0, (f"{what} ray spawned on the wrong side at p={p.p[src[wrong[0]]]}, "
                                 f"n={p.n[src[wrong[0]]]}: sdf(origin)={d0[wrong[0]]}")
        _check_no_crossing(name, spawned, f"{what} rays")


SMOOTH_CASES = [c for c in CASES if SCENES[c.values[0]].smooth]


@pytest.mark.parametrize("name,omega", SMOOTH_CASES)
def test_spawn_does_not_rehit_its_own_surface(name, omega):
    """On smooth surfaces a spawned ray starts at least one hit threshold off the surface, on the
    side it leaves to, so the marcher cannot stop at once (self-intersection), at scales 0.01..100.

    SPAWN_OFFSET = 2.5 thresholds along the normal from a point within one threshold of the surface
    gives >= 1.5 thresholds on a flat surface; curvature and f32 rounding (|p| ~ 100 at scale 100)
    eat a little of that, and 1.0 is what the marcher needs.
    """
    result = run(name, omega)
    geo = geometry(name)
    p = result.primary
    for what, spawned, src in (("reflected", result.refl, result.refl_from),
                               ("transmitted", result.trans, result.trans_from)):
        eps = p.eps[src]
        leaving_out = np.einsum("ij,ij->i", spawned.d, p.n[src]) > 0
        d0 = sdf(geo, spawned.o) * np.where(leaving_out, 1.0, -1.0)
        worst = int(np.argmin(d0 / eps))
        assert d0[worst] >= eps[worst], (f"{what} ray spawned {d0[worst] / eps[worst]:.2f} thresholds off "
                                         f"the surface at {p.p[src[worst]]}")
        immediate = (spawned.hit == 1) & (spawned.work == 1)
        assert not immediate.any(), f"{immediate.sum()} {what} rays re-hit their own surface at t = 0"


def _convex_edge_hits(rng, kind, n):
    """Rays from outside aimed exactly at box edges or the cone's base rim."""
    if kind == "box":
        half = 0.5 * np.array([1.2, 0.8, 0.5])
        pts = rng.uniform(-1, 1, (n, 3)) * half
        free = rng.integers(0, 3, n)
        fixed = rng.choice([-1.0, 1.0], (n, 3)) * half
        for a in range(3):
            pts[free != a, a] = fixed[free != a, a]
    else:
        u = rng.uniform(0, 2 * np.pi, n)
        pts = np.stack([0.5 * np.cos(u), np.full(n, -0.5), 0.5 * np.sin(u)], 1)
    d = random_directions(rng, n)
    o = pts + 0.5 * d
    return o, -d


@pytest.mark.xfail(strict=True, reason="at a convex edge a ray refracted nearly parallel to the other "
                                       "face cannot be given a threshold of clearance by any offset")
@pytest.mark.parametrize("kind", ["box", "cone"])
def test_spawn_at_convex_edges(kind):
    """A ray refracted into a solid at (within a threshold of) a convex edge starts inside it.

    Known limitation: spawn() offsets along the difference normal, which near an edge blends the
    two faces' normals, then pushes further along it until the origin clears every surface by
    1.5 thresholds (this took the box from 37% to about 23% of such rays, the cone rim from 73% to
    58%). A ray refracted nearly parallel to the other face still starts within a threshold of it,
    and no offset can change that without moving the ray; it then crosses that face at once.
    """
    geo = geometry(kind)
    geo.set_march(_march(SCENES[kind], 1.6))
    rng = np.random.default_rng(7)
    o, d = _convex_edge_hits(rng, kind, 4000)
    keep = ref_scene(SCENES[kind].objects, o) > 0.01
    r = trace(geo, o[keep], d[keep], 3.0)
    ok = (r.hit == 1) & (r.trans_valid == 1)
    assert ok.sum() > 1000
    d0 = sdf(geo, r.trans_o[ok])
    assert np.all(d0 < -r.eps[ok]), f"{np.mean(d0 >= -r.eps[ok]):.0%} of refracted rays start off the solid"


def test_camera_inside_sphere_sees_inner_surface():
    """Origins inside a sphere hit its inner surface (back face) at the analytic exit distance.

    The marcher stops within one threshold of the surface, i.e. about THRESHOLD / cos(exit angle)
    before the exit along the ray (exactly: where the chord is THRESHOLD deep); rays exiting within
    ~6 degrees of grazing are left out of the distance check (and kept for the face check).
    """
    radius = 0.6
    geo = geometry("sphere")
    rng = np.random.default_rng(11)
    o = random_directions(rng, 3000) * (radius * rng.uniform(0.0, 0.999, 3000) ** (1 / 3))[:, None]
    d = random_directions(rng, 3000)
    for omega in OMEGAS:
        geo.set_march(_march(SCENES["sphere"], omega))
        r = trace(geo, o, d, 10.0)
        assert np.all(r.hit == 1) and np.all(r.front_face == 0)
        b = np.einsum("ij,ij->i", r.o, r.d)
        t_exit = -b + np.sqrt(b * b - (np.einsum("ij,ij->i", r.o, r.o) - radius ** 2))
        exit_point = r.o + t_exit[:, None] * r.d
        cos_exit = np.einsum("ij,ij->i", r.d, exit_point / radius)
        f32 = 4e-7  # rounding of o + t d and of |p| at |p| < 1
        early = t_exit - r.t
        assert np.all(early >= -f32)
        # The last point of the chord within THRESHOLD of the sphere (|p| = R - THRESHOLD): a little
        # more than THRESHOLD / cos before the exit, since the sphere curves towards the chord.
        rc = radius * cos_exit
        latest = rc - np.sqrt(np.maximum(rc * rc - 2 * radius * THRESHOLD + THRESHOLD ** 2, 0.0))
        clear = cos_exit > 0.1
        assert np.all(early[clear] <= latest[clear] + f32)
        # The normal there is the outward radial direction (tetrahedral differences, h = eps/2).
        assert np.allclose(r.n, r.p / np.linalg.norm(r.p, axis=1, keepdims=True), atol=1e-3)


@pytest.mark.parametrize("kind", ["box", "cone"])
def test_normals_are_unit_at_edges_corners_and_apex(kind):
    """normal() and surface().n_geo stay unit vectors where the SDF has a kink: box edges and corners,
    the cone's apex and rim; exactly on them, and a little outside and inside."""
    geo = geometry(kind)
    geo.set_march(_march(SCENES[kind], 1.6))
    if kind == "box":
        half = 0.5 * np.array([1.2, 0.8, 0.5])
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], np.float64)
        corners = signs * half
        edges = np.concatenate([corners * np.array(m) for m in ((0.5, 1, 1), (1, 0.5, 1), (1, 1, 0.5))])
        special = np.concatenate([corners, edges])
        outward = special / np.linalg.norm(special, axis=1, keepdims=True)
    else:
        u = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        rim = np.stack([0.5 * np.cos(u), np.full_like(u, -0.5), 0.5 * np.sin(u)], 1)
        special = np.concatenate([[[0.0, 0.5, 0.0]], rim])
        outward = np.concatenate([[[0.0, 1.0, 0.0]], rim / np.linalg.norm(rim, axis=1, keepdims=True)])
    pts = np.concatenate([special + s * outward for s in (-1e-3, -THRESHOLD, 0.0, THRESHOLD, 1e-3)])
    out = np.concatenate([outward] * 5)
    for h in (1e-5, 5e-5, 1e-3):
        n = normals(geo, pts, h)
        assert np.all(np.isfinite(n))
        assert np.abs(np.linalg.norm(n, axis=1) - 1.0).max() < 1e-5
        assert np.all(np.einsum("ij,ij->i", n, out) > 0.0), "normal points into the solid"
    # Through surface(): rays aimed at those points from outside.
    rng = np.random.default_rng(3)
    target = np.repeat(special, 50, axis=0)
    d = random_directions(rng, len(target))
    d *= np.sign(np.einsum("ij,ij->i", d, np.repeat(outward, 50, axis=0)))[:, None]
    r = trace(geo, target + 0.3 * d, -d, 1.0)
    hit = r.hit == 1
    assert hit.mean() > 0.5
    assert np.abs(np.linalg.norm(r.n[hit], axis=1) - 1.0).max() < 1e-5


@pytest.mark.parametrize("name", ["plane", "box"])
def test_relaxed_step_onto_a_flat_face_is_taken_back(name):
    """Head-on at a flat face the SDF falls linearly along the ray, so after a relaxed step
    radius + prev_radius == step exactly: the unbounding spheres only touch, at the surface, and the
    step has landed past it. The marcher must take it back (3 evaluations: step, back, hit) rather
    than accept the far side and oscillate across the surface until it converges."""
    geo = geometry(name)
    geo.set_march(_march(SCENES[name], 1.6))
    rng = np.random.default_rng(17)
    n = 500
    height = rng.uniform(0.05, 3.0, n)
    if name == "plane":
        normal = np.array([0.2, 1.0, -0.1]) / np.linalg.norm([0.2, 1.0, -0.1])
        foot = rng.uniform(-1, 1, (n, 3))
        foot -= (foot @ normal - 0.1)[:, None] * normal  # onto the plane p . n = offset
    else:
        normal = np.array([0.0, 0.0, 1.0])
        foot = np.stack([rng.uniform(-0.5, 0.5, n), rng.uniform(-0.3, 0.3, n), np.full(n, 0.25)], 1)
    o = foot + height[:, None] * normal
    hit, work, t = intersect(geo, o, np.broadcast_to(-normal, o.shape), 10.0)
    assert np.all(hit == 1)
    assert np.all(np.abs(t - height) < THRESHOLD + 1e-6)
    assert work.max() <= 3, f"up to {work.max()} steps head-on (mean {work.mean():.1f})"


@pytest.mark.parametrize("cone_spread", [0.0, 2e-3])
def test_grazing_rays_over_a_plane(cone_spread):
    """Rays at 1e-3 to 0.9 rad over the floor, from 0.5 mm to 5 cm above it, either hit it where the
    analytic ray meets it or miss (out of steps), never elsewhere and never NaN.

    A hit means |sdf| < threshold at a point on the ray, and the ray's height above the plane is
    (t_exact - t) sin(theta), so the hit lies between the analytic t = h / sin(theta) and
    threshold / sin(theta) before it: a relative error of at most threshold / h (2e-3 at 5 cm,
    0.2 at 0.5 mm). With a pixel cone the threshold grows to cone_spread * t at distance t.
    A miss can only come from the step budget: at 1e-3 rad each step gains ~1e-3 of the height.
    """
    geo = make_geometry(node("plane"))
    geo.set_march(MarchSettings(min_threshold=THRESHOLD, max_steps=MAX_STEPS, max_distance=1e4, over_relaxation=1.6))
    rng = np.random.default_rng(5)
    n = 3000
    theta = 10.0 ** rng.uniform(-3.0, math.log10(0.9), n)
    phi = rng.uniform(0.0, 2 * np.pi, n)
    height = 0.05 * 10.0 ** rng.uniform(-2, 0, n)  # 0.5 mm .. 5 cm above the floor
    o = np.stack([rng.uniform(-1, 1, n), height, rng.uniform(-1, 1, n)], 1)
    d = np.stack([np.cos(theta) * np.cos(phi), -np.sin(theta), np.cos(theta) * np.sin(phi)], 1)
    r = trace(geo, o, d, 200.0, cone_spread=cone_spread)
    assert np.all(np.isfinite(r.t)) and np.all(np.isfinite(r.p[r.hit == 1]))
    hit = r.hit == 1
    t_exact = r.o[:, 1] / -r.d[:, 1]  # with the f32 origin and direction the kernel saw
    thr = np.maximum(THRESHOLD, cone_spread * r.t)
    f32 = 1e-6 * (1.0 + t_exact)
    assert np.all(r.p[hit, 1] > -f32[hit]), "hit below the floor"
    assert np.all(r.p[hit, 1] < thr[hit] + f32[hit]), "hit above the floor"
    early = t_exact - r.t
    assert np.all(early[hit] >= -f32[hit] / np.sin(theta[hit]))
    assert np.all(early[hit] <= (thr[hit] + f32[hit]) / np.sin(theta[hit]))
    if cone_spread == 0.0:
        # Relative error of the hit distance: at most THRESHOLD / h (h = the origin's height).
        rel = np.abs(early[hit]) / t_exact[hit]
        assert np.all(rel <= THRESHOLD / r.o[hit, 1] + 1e-6)
    # A miss is a miss for lack of steps (the analytic hit is within reach), and only at low angles.
    miss = ~hit
    assert np.all(r.work[miss] >= MAX_STEPS)
    assert hit[theta > 0.1].all()
    assert hit.mean() > 0.5


def test_over_relaxation_does_not_add_steps_on_the_showcase():
    """Camera rays of the showcase scene: omega = 1.6 takes no more steps on average than plain sphere
    tracing and finds the same surfaces."""
    scene = load_scene(REPO / "assets/scenes/showcase.toml")
    geo = SdfGeometry(scene, scene.material_index)
    cam = CameraFrame.from_spec(scene.camera)
    width, height = 96, 54
    x, y = np.meshgrid((np.arange(width) + 0.5) / width, (np.arange(height) + 0.5) / height)
    tan_half = math.tan(math.radians(cam.fov) / 2)
    aspect = scene.render.width / scene.render.height
    d = (np.asarray(cam.forward) + ((2 * x - 1) * tan_half * aspect).reshape(-1, 1) * np.asarray(cam.right)
         + ((2 * y - 1) * tan_half).reshape(-1, 1) * np.asarray(cam.up))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.broadcast_to(np.asarray(cam.position), d.shape)
    spread = 2.0 * tan_half / scene.render.height  # the camera's pixel cone at full resolution
    steps = {}
    hits = {}
    for omega in OMEGAS:
        geo.set_march(MarchSettings(**{**scene.render.march.__dict__, "over_relaxation": omega}))
        hit, work, t = intersect(geo, o, d, 1e30, cone_spread=spread)
        steps[omega] = work.mean()
        hits[omega] = (hit, t)
    assert steps[1.6] <= steps[1.0], f"mean steps {steps[1.6]:.2f} with omega 1.6, {steps[1.0]:.2f} without"
    (h16, t16), (h10, t10) = hits[1.6], hits[1.0]
    assert np.mean(h16 == h10) > 0.995
    both = (h16 == 1) & (h10 == 1)
    assert np.median(np.abs(t16[both] - t10[both])) < 1e-2

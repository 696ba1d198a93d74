"""Every geometry kind returns hit points on its surface, from outside and from inside (flat kinds:
from both sides): o + t d lies on the surface, and surface().p lies on it and equals o + t d.

One case per kind: triangles (a closed icosphere), analytic spheres, quads, discs and Bezier
surfaces of revolution (a closed convex solid, rotated and non-uniformly scaled), together in one
mesh scene behind its BVH; and the eight SDF primitives (rotated, scaled) in one sphere-traced
scene. Both scenes sit ~30 m from the origin, so the rounding of world positions is part of the
test, and their objects are 3 m apart, further than any ray here travels.

Rays are aimed at random surface points X (unit outward normal N) from o = X + side l w, with
w . N >= MIN_COSINE and l random; an origin is kept only where the exact reference puts it on the
side asked for, at least MARGIN from the surface. Checks, for every kind and side:
- every ray hits the object aimed at, on the side it came from (front_face);
- dist(o + t d) <= TOL_HIT and dist(surface().p) <= TOL_ON (dist: the exact distance to the
  analytic surface, float64), |surface().p - (o + t d)| <= TOL_AGREE;
- the hit is not beyond X, where the ray would have gone through the surface (the far root of a
  sphere, a later patch): t <= (X - o) . d + (TOL_HIT + 2 lateral) / cos, where lateral is how far
  the f32 ray passes from X (it moves the crossing of the tangent plane by lateral / cos; the
  curvature adds lateral^2 / R, far less) and a point TOL_HIT off the surface lies TOL_HIT / cos
  along the ray. (A hit before X must still lie on the surface, which the checks above hold it
  to; on the convex objects, all but the torus, there is no such point.)

Tolerances, with u = 2^-24 (f32 unit roundoff), m = |o - c| + t + R (c the object's centre or
corner, R its size) bounding the magnitudes of the local computations (offsets from the object)
and W = |o| + t + |X| + R those of world positions; counts are first order with every rounding
against us, and the constants leave about a factor 2 for the terms the counts leave out:
- triangles: TOL_HIT = TOL of tests/geometry/hit_bounds.py (128 u (t + L) kappa / cos);
  surface().p is b0 v0 + b1 v1 + b2 v2 in f32, 5 roundings of at most max |v|:
  TOL_ON = TOL + 5u max|v|.
- spheres, quads, discs: t comes from ~10 roundings of vectors no longer than m (o - c, the
  closest-approach vector, plane offsets); each moves the point off the surface along the normal
  by at most u m (a slanted ray's 1/cos error along the ray projects back onto the normal with
  cos; a sphere's sqrt(disc) = R cos_i likewise): TOL_HIT = 32u m. surface().p projects the f32
  point back onto the surface in world coordinates (sphere: c + R normalize(p - c); quad:
  corner + a e_u + b e_v; disc: p - ((p - c) . n) n), <= 8 roundings of at most W: TOL_ON = 16u W.
- Bezier: Newton stops at |S(u, phi) - (o + s d)| <= eps (object units, RELATIVE_EPS of the
  object's size) as evaluated in f32: the evaluation (Bernstein sums, cos, sin, the ray) adds ~10
  roundings of local magnitudes, the world-to-object map 3 of world ones, and the object's matrix
  A stretches them by at most its condition number: TOL_HIT = |A| eps + cond(A) (32u m + 8u W);
  surface().p is A S + a at the hit's (u, phi), dist measured against S(u, phi) in float64:
  TOL_ON = 16u cond(A) W.
- SDF: the marcher stops where the f32 distance at fl(o + t d) is below the hit threshold; that
  distance is off the exact one by the rounding of the object's transform (p - translation: 2u W)
  and of the primitive (~8 roundings of at most m), and fl(o + t d) is 2u W from o + t d:
  TOL_HIT = threshold + 16u m + 4u W. surface().p is fl(o + t d): TOL_AGREE = 2u W,
  TOL_ON = TOL_HIT + 2u W.
- elsewhere TOL_AGREE = TOL_HIT + TOL_ON + 2u W: surface().p is the projection of a point within
  TOL_HIT + 2u W of o + t d, rounded by TOL_ON.
"""
import dataclasses
from dataclasses import dataclass
from typing import Callable

import numpy as np
import pytest
import trimesh
from matplotlib.path import Path as Polygon

from renderer.geometry import bezier as bz
from renderer.geometry.bezier_device import RELATIVE_EPS
from renderer.geometry.mesh_data import MeshData
from renderer.scene.description import Transform
from tests.geometry.hit_bounds import (U, interior_barycentrics, point_triangle_distance, tilted, triangle_shape,
                                       triangle_tolerance, unit)
from tests.geometry.mesh_helpers import SurfaceProbe, geometry_from
from tests.sdf.sdf_helpers import PRIMITIVES, make_geometry, node, ref_node, ref_scene

P = SurfaceProbe  # column names
OFFSET = np.array([12.0, -4.0, 25.0])  # both scenes sit here, ~30 m from the origin
SPACING = 3.0  # between objects: further than any ray here travels before its hit
MIN_COSINE = 0.2  # incidence at X up to 78 degrees
MARGIN = 1e-3  # an origin at least this far from the surface, on the side asked for
REACH = {1: (0.05, 1.0), -1: (0.02, 0.5)}  # range of l (metres) from outside (front), from inside (back)
SDF_THRESHOLD = 1e-4  # MarchSettings.min_threshold: rays without a cone hit below it
MESH_KINDS = ("triangle", "sphere", "quad", "disc", "bezier")
RAYS = 600  # per kind (SDF: per primitive) and side


def spot(i):
    return OFFSET + np.array([SPACING * i, 0.0, 0.0])


@dataclass
class Kind:
    """One geometry kind: where its surface is and how far a point is from it."""
    sample: Callable  # (rng, n) -> (X, N, object id) on the surface
    side: Callable  # (points) -> signed distance-like: > 0 outside / in front, < 0 inside / behind
    distance: Callable  # (points, probe rows) -> exact distance to the surface the hit names
    tolerances: Callable  # (d, probe rows, m, W) -> (TOL_HIT, TOL_ON, TOL_AGREE) arrays
    centre: Callable  # (object ids) -> c (n, 3): where the local computations are anchored
    size: float  # R
    owns: Callable = None  # (probe rows, object ids) -> each hit is on the object aimed at


def closed_form_tolerances(d, out, m, w):
    hit, on = 32 * U * m, 16 * U * w
    return hit, on, hit + on + 2 * U * w


def anchored(point):
    return lambda ids: np.tile(point, (len(ids), 1))


# --- the mesh scene ----------------------------------------------------------------------------

ICOSPHERE_RADIUS = 0.6
SPHERE_RADIUS = 0.6
QUAD_ROTATION = Transform(rotate=(25.0, 40.0, -15.0)).rotation_matrix()
QUAD_EDGES = QUAD_ROTATION @ np.diag([1.2, 1.0, 0.8])  # columns: edge u, normal direction, edge v
DISC_NORMAL = unit(np.array([0.3, 1.0, -0.5]))
DISC_RADIUS = 0.6
# A closed convex solid of revolution: flat bottom from the axis, a belly, a dome back to the axis
# (counter-clockwise, so normals point out).
BEZIER_PROFILE = [(0.0, -0.4), (0.5, -0.4), (0.6, -0.3), (0.6, -0.1), (0.6, 0.2), (0.3, 0.4), (0.0, 0.4)]


def bezier_matrix():
    m = np.eye(4)
    m[:3, :3] = Transform(rotate=(20.0, 30.0, -10.0)).rotation_matrix() @ np.diag([1.2, 0.8, 1.0])
    m[:3, 3] = spot(4)
    return m


class MeshWorld:
    """One mesh scene with an object of every mesh kind, its geometry and a probe."""

    def kind(self, name) -> Kind:
        lo, hi = self.ranges[name]
        return dataclasses.replace(getattr(self, name)(),
                                   owns=lambda out, ids: (out[:, P.PRIM] >= lo) & (out[:, P.PRIM] < hi))

    def __init__(self):
        ball = trimesh.creation.icosphere(subdivisions=2, radius=ICOSPHERE_RADIUS)
        self.tris = (ball.vertices[np.asarray(ball.faces)] + spot(0)).astype(np.float32)
        self.quad_rows = np.array([spot(2) - 0.5 * QUAD_EDGES[:, 0] - 0.5 * QUAD_EDGES[:, 2],
                                   QUAD_EDGES[:, 0], QUAD_EDGES[:, 2]])  # corner, edge u, edge v
        self.cubics = bz.cubic_segments(BEZIER_PROFILE, 3)
        self.matrix = bezier_matrix()
        zero = np.zeros(1, np.int32)
        self.data = MeshData(tri_vertices=self.tris, tri_material=np.zeros(len(self.tris), np.int32),
                             spheres=np.array([[*spot(1), SPHERE_RADIUS]], np.float32), sphere_material=zero,
                             quads=self.quad_rows[None].astype(np.float32), quad_material=zero,
                             discs=np.array([[*spot(3), *DISC_NORMAL, DISC_RADIUS]], np.float32),
                             disc_material=zero, **bz.bezier_fields([(self.cubics, self.matrix, 0, 4, 16)]))
        self.probe = SurfaceProbe(geometry_from(self.data))
        ends = self.data.range_ends()
        self.ranges = dict(zip(MESH_KINDS, zip(np.concatenate([[0], ends[:-1]]), ends)))
        # the profile as a dense polygon closed along the axis: inside/outside of the solid
        u = np.linspace(0.0, 1.0, 1001)
        self.polygon = Polygon(np.concatenate([bz.curve_point(c[None], u[:, None])[0].reshape(-1, 2)
                                               for c in self.cubics]))

    # triangles -----------------------------------------------------------------------------------
    def triangle(self):
        v = self.tris.astype(np.float64)
        _, _, normal = triangle_shape(v)

        def sample(rng, n):
            f = rng.integers(0, len(v), n)
            return np.einsum("ni,nij->nj", interior_barycentrics(rng, n), v[f]), normal[f], np.zeros(n, int)

        def side(p):  # a convex polyhedron: the largest plane offset is its signed distance inside
            return np.max([((p - v[f, 0]) * normal[f]).sum(axis=1) for f in range(len(v))], axis=0)

        def distance(p, out):
            return point_triangle_distance(p, v[out[:, P.PRIM].astype(int)])

        def tolerances(d, out, m, w):
            tri = v[out[:, P.PRIM].astype(int)]
            longest, kappa, n = triangle_shape(tri)
            hit = triangle_tolerance(out[:, P.T], longest, kappa, (n * d).sum(axis=1))
            on = hit + 5 * U * np.abs(tri).max(axis=(1, 2))
            return hit, on, hit + on + 2 * U * w

        return Kind(sample, side, distance, tolerances, anchored(spot(0)), ICOSPHERE_RADIUS)

    # analytic spheres ---------------------------------------------------------------------------
    def sphere(self):
        c = spot(1)

        def sample(rng, n):
            nrm = unit(rng.normal(size=(n, 3)))
            return c + SPHERE_RADIUS * nrm, nrm, np.zeros(n, int)

        def side(p):
            return np.linalg.norm(p - c, axis=1) - SPHERE_RADIUS

        return Kind(sample, side, lambda p, out: np.abs(side(p)), closed_form_tolerances, anchored(c), SPHERE_RADIUS)

    # quads and discs: flat, hit from both sides ------------------------------------------------------
    def quad(self):
        corner, eu, ev = self.quad_rows
        normal = unit(np.cross(eu, ev))
        halves = np.array([[corner, corner + eu, corner + eu + ev], [corner, corner + eu + ev, corner + ev]])

        def sample(rng, n):
            a, b = rng.uniform(0.02, 0.98, (2, n))
            return corner + a[:, None] * eu + b[:, None] * ev, np.tile(normal, (n, 1)), np.zeros(n, int)

        def distance(p, out):
            return np.min([point_triangle_distance(p, np.broadcast_to(h, (len(p), 3, 3))) for h in halves], axis=0)

        return Kind(sample, lambda p: (p - corner) @ normal, distance, closed_form_tolerances, anchored(corner),
                    float(np.linalg.norm(eu + ev)))

    def disc(self):
        c = spot(3)
        a = unit(np.cross(DISC_NORMAL, [1.0, 0.0, 0.0]))
        b = np.cross(DISC_NORMAL, a)

        def sample(rng, n):
            r = DISC_RADIUS * np.sqrt(rng.uniform(0.0, 0.96, n))
            phi = rng.uniform(0.0, 2 * np.pi, n)
            x = c + (r * np.cos(phi))[:, None] * a + (r * np.sin(phi))[:, None] * b
            return x, np.tile(DISC_NORMAL, (n, 1)), np.zeros(n, int)

        def distance(p, out):
            height = (p - c) @ DISC_NORMAL
            radial = np.linalg.norm(p - c - height[:, None] * DISC_NORMAL, axis=1)
            return np.hypot(height, np.maximum(radial - DISC_RADIUS, 0.0))

        return Kind(sample, lambda p: (p - c) @ DISC_NORMAL, distance, closed_form_tolerances, anchored(c),
                    DISC_RADIUS)

    # Bezier surfaces of revolution -------------------------------------------------------------------
    def bezier(self):
        lin, trans = self.matrix[:3, :3], self.matrix[:3, 3]
        inverse = np.linalg.inv(lin)
        stretch = np.linalg.norm(lin, 2)
        condition = np.linalg.cond(lin)
        size_obj = np.abs(self.cubics).max()
        first = self.ranges["bezier"][0]

        def world(curve, u, phi):
            """World point and unit outward normal at (curve, u, phi) (float64)."""
            ctrl = self.cubics[curve]
            s, _, _ = bz.surface_point(ctrl, u, phi)
            _, dc = bz.curve_point(ctrl, u)
            n_obj = np.stack([dc[..., 1] * np.cos(phi), -dc[..., 0], dc[..., 1] * np.sin(phi)], axis=-1)
            return s @ lin.T + trans, unit(n_obj @ inverse)

        def sample(rng, n):
            curve = rng.integers(0, len(self.cubics), n)
            x, nrm = world(curve, rng.uniform(0.02, 0.98, n), rng.uniform(0.0, 2 * np.pi, n))
            return x, nrm, np.zeros(n, int)

        def side(p):
            q = (p - trans) @ inverse.T
            meridian = np.stack([np.hypot(q[:, 0], q[:, 2]), q[:, 1]], axis=1)
            # The polygon's inside flag, and the distance to its nearest vertex (they are ~1e-3
            # apart, so it is within 5e-4 of the distance to the curve): enough to keep origins
            # clear of the surface on the side asked for.
            gap = np.min(np.linalg.norm(meridian[:, None] - self.polygon.vertices[None], axis=2), axis=1)
            return np.where(self.polygon.contains_points(meridian), -gap, gap) / np.linalg.norm(inverse, 2)

        def distance(p, out):
            patch = out[:, P.PRIM].astype(int) - first
            curve = self.data.bezier_patch_curve[patch]
            s, _ = world(curve, out[:, P.BARY][:, 0].astype(np.float64), out[:, P.BARY][:, 1].astype(np.float64))
            return np.linalg.norm(p - s, axis=1)

        def tolerances(d, out, m, w):
            hit = stretch * RELATIVE_EPS * size_obj + condition * (32 * U * m + 8 * U * w)
            on = 16 * U * condition * w
            return hit, on, hit + on + 2 * U * w

        return Kind(sample, side, distance, tolerances, anchored(trans), float(stretch * size_obj))


@pytest.fixture(scope="module")
def mesh_world():
    return MeshWorld()


# --- the SDF scene -------------------------------------------------------------------------------

SDF_OBJECTS = tuple(
    node(kind, translate=tuple(OFFSET + [SPACING * i, 0.0, -SPACING]), rotate=(30.0 * i, 17.0, -11.0 * i),
         scale=0.9 if i % 2 else 1.1)
    for i, kind in enumerate(k for k in PRIMITIVES if k != "plane")
) + (node("plane", normal=(0.1, 1.0, -0.2), translate=tuple(OFFSET + [0.0, -SPACING, 0.0])),)


class SdfWorld:
    def __init__(self):
        self.geometry = make_geometry(*SDF_OBJECTS, min_threshold=SDF_THRESHOLD)
        self.probe = SurfaceProbe(self.geometry)
        # node ids of the objects (the scene gave them a material, so match kind and placement)
        order = self.geometry.program.order
        self.node_id = [next(i for i, n in enumerate(order) if (n.kind, n.transform) == (o.kind, o.transform))
                        for o in SDF_OBJECTS]

    def kind(self, name="sdf") -> Kind:
        def gradient(obj, p, h=1e-6):
            e = np.eye(3) * h
            return np.stack([(ref_node(obj, p + e[k]) - ref_node(obj, p - e[k])) / (2 * h) for k in range(3)], axis=1)

        def sample(rng, n):
            xs, ns, ids = [], [], []
            for i, obj in enumerate(SDF_OBJECTS):
                centre = np.asarray(obj.transform.translate)
                if obj.kind == "plane":  # a patch of the plane, away from the other objects
                    p = centre + rng.uniform(-1.0, 1.0, (4 * n, 3)) * [SPACING, 0.3, SPACING] + [SPACING, 0, 0]
                else:
                    p = centre + rng.uniform(-0.8, 0.8, (4 * n, 3))
                for _ in range(3):  # onto the surface: an exact SDF's gradient points to the nearest point
                    p = p - ref_node(obj, p)[:, None] * unit(gradient(obj, p))
                g = unit(gradient(obj, p))
                # away from edges and corners, where the normal is not defined: same gradient just
                # inside and just outside
                smooth = ((unit(gradient(obj, p - 0.01 * g)) * unit(gradient(obj, p + 0.01 * g))).sum(axis=1) > 0.9999)
                keep = np.flatnonzero(smooth & (np.abs(ref_node(obj, p)) < 1e-9))[:n]
                assert len(keep) == n, f"too few smooth surface samples on the {obj.kind}"
                xs.append(p[keep])
                ns.append(g[keep])
                ids.append(np.full(n, i))
            return np.concatenate(xs), np.concatenate(ns), np.concatenate(ids)

        def side(p):
            return ref_scene(SDF_OBJECTS, p)

        def tolerances(d, out, m, w):
            hit = SDF_THRESHOLD + 16 * U * m + 4 * U * w
            return hit, hit + 2 * U * w, 2 * U * w

        def centre(ids):
            return np.array([SDF_OBJECTS[i].transform.translate for i in ids])

        def owns(out, ids):
            return out[:, P.PRIM].astype(int) == np.asarray(self.node_id)[ids]

        # size: the primitives' parameters are of order 1 (sdf_helpers), scaled by 0.9 or 1.1
        return Kind(sample, side, lambda p, out: np.abs(side(p)), tolerances, centre, 1.0, owns)


@pytest.fixture(scope="module")
def sdf_world():
    return SdfWorld()


# --- the property ------------------------------------------------------------------------------------

def aim(rng, x, normal, side):
    """f32 rays from side (+1 outside / front, -1 inside / back) at the points x."""
    w = tilted(rng, normal, MIN_COSINE)
    o = (x + (side * rng.uniform(*REACH[side], len(x)))[:, None] * w).astype(np.float32)
    return o, unit(x - o).astype(np.float32)


def check(name, kind, probe, rng, side):
    x, normal, ids = kind.sample(rng, RAYS)
    o, d = aim(rng, x, normal, side)
    keep = side * kind.side(o.astype(np.float64)) >= MARGIN
    for i in np.unique(ids):  # enough rays from this side on every object
        assert keep[ids == i].mean() > 0.25, f"{name}: few origins on the side asked for ({keep[ids == i].mean():.0%})"
    x, normal, ids, o, d = x[keep], normal[keep], ids[keep], o[keep].astype(np.float64), d[keep].astype(np.float64)
    out = probe.shoot(o, d).astype(np.float64)
    where = f"{name} from {'outside' if side > 0 else 'inside'}"
    assert (out[:, P.HIT] == 1).all(), f"{where}: {np.count_nonzero(out[:, P.HIT] != 1)} aimed rays missed"
    assert kind.owns(out, ids).all(), f"{where}: a ray hit another object"
    assert (out[:, P.FRONT] == (side > 0)).all(), f"{where}: front_face says the other side"
    along = o + out[:, P.T, None] * d
    p = out[:, P.P]
    local = np.linalg.norm(o - kind.centre(ids), axis=1) + out[:, P.T] + kind.size
    world = np.linalg.norm(o, axis=1) + out[:, P.T] + np.linalg.norm(x, axis=1) + kind.size
    tol_hit, tol_on, tol_agree = kind.tolerances(d, out, local, world)
    for label, error, tol in (("o + t d off the surface", kind.distance(along, out), tol_hit),
                              ("surface().p off the surface", kind.distance(p, out), tol_on),
                              ("surface().p is not o + t d", np.linalg.norm(p - along, axis=1), tol_agree)):
        worst = int(np.argmax(error / tol))
        assert (error <= tol).all(), (f"{where}: {label} by {error[worst]:.3g} (tolerance {tol[worst]:.3g}) "
                                      f"at {along[worst]}, ray {o[worst]} + t {d[worst]}")
    t_x = ((x - o) * d).sum(axis=1)
    lateral = np.linalg.norm(x - (o + t_x[:, None] * d), axis=1)
    allowed = (tol_hit + 2 * lateral) / np.abs((normal * d).sum(axis=1))
    late = out[:, P.T] - t_x
    beyond = late > allowed
    assert not beyond.any(), f"{where}: {np.count_nonzero(beyond)} hits lie beyond the aimed point ({late[beyond]})"


WORLDS = {**{name: "mesh_world" for name in MESH_KINDS}, "sdf": "sdf_world"}  # kind -> fixture


@pytest.mark.parametrize("name", WORLDS)
def test_hit_points_lie_on_the_surface_from_both_sides(name, request):
    world = request.getfixturevalue(WORLDS[name])
    rng = np.random.default_rng(31 + list(WORLDS).index(name))
    for side in (1, -1):
        check(name, world.kind(name), world.probe, rng, side)

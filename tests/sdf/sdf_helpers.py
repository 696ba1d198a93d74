"""Shared pieces of the SDF tests: scenes built in code, numpy reference distances, test kernels.

The kernels take the geometry as a template argument, so each SdfGeometry compiles its own copy:
tests share geometries through module-scoped fixtures or caches and batch thousands of rays per launch.
"""

import numpy as np
import taichi as ti

from renderer.geometry.interface import Ray
from renderer.materials import microfacet as mf
from renderer.scene.description import (
    CameraSpec,
    EnvironmentSpec,
    MarchSettings,
    MaterialSpec,
    RenderSettings,
    Scene,
    SdfNode,
    Transform,
)
from shaders_sdf.geometry import SdfGeometry

vec3 = ti.math.vec3
MATERIAL = "m"

# Parameters of every primitive as the tests use them (sizes of order 1, smallest feature 0.15).
PRIMITIVE_PARAMS = {
    "sphere": {"radius": 0.6},
    "box": {"size": (1.2, 0.8, 0.5)},
    "rounded_box": {"size": (1.0, 0.7, 0.9), "radius": 0.15},
    "torus": {"major_radius": 0.5, "minor_radius": 0.15},
    "capsule": {"height": 0.8, "radius": 0.25},
    "cylinder": {"height": 0.9, "radius": 0.4},
    "cone": {"height": 1.0, "radius": 0.5},
    "plane": {"normal": (0.0, 1.0, 0.0), "offset": 0.0},
}
PRIMITIVES = tuple(PRIMITIVE_PARAMS)


# --- scenes built in code ----------------------------------------------------------------------


def node(kind: str, *children: SdfNode, translate=(0.0, 0.0, 0.0), rotate=(0.0, 0.0, 0.0),
         scale: float = 1.0, material: str | None = None, **params) -> SdfNode:
    """An SdfNode as the loader would build it (parameters sorted by name)."""
    if kind in PRIMITIVE_PARAMS:
        params = {**PRIMITIVE_PARAMS[kind], **params}
    if kind == "plane":
        n = np.asarray(params["normal"], np.float64)
        params["normal"] = tuple(float(c) for c in n / np.linalg.norm(n))
    if kind == "repeat":
        params.setdefault("limit", None)
    return SdfNode(kind=kind, params=tuple(sorted(params.items())), children=tuple(children),
                   transform=Transform(tuple(map(float, translate)), tuple(map(float, rotate)), float(scale)),
                   material=material)


def make_scene(*objects: SdfNode, materials=(MaterialSpec(MATERIAL),), **march) -> Scene:
    """A scene of `objects`; those without a material get the first of `materials` (by default
    one diffuse material named 'm')."""
    objects = tuple(o if o.material is not None else SdfNode(o.kind, o.params, o.children, o.transform,
                                                             materials[0].name)
                    for o in objects)
    return Scene(name="test", path=None, geometry="sdf", camera=CameraSpec(),
                 render=RenderSettings(march=MarchSettings(**march)), environment=EnvironmentSpec(),
                 materials=tuple(materials), sdf_objects=objects)


def make_geometry(*objects: SdfNode, materials=(MaterialSpec(MATERIAL),), **march) -> SdfGeometry:
    scene = make_scene(*objects, materials=materials, **march)
    return SdfGeometry(scene, scene.material_index)


def set_march(geometry: SdfGeometry, **march) -> None:
    geometry.set_march(MarchSettings(**march))


# --- numpy references (float64), written from the geometric definitions ----------------------


def _seg_dist2d(p, a, b):
    """Distance from 2D points p (N,2) to the segment ab."""
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    ab = b - a
    t = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def ref_sphere(p, radius):
    return np.linalg.norm(p, axis=1) - radius


def ref_box(p, size):
    """Outside: distance to the clamped (closest) point; inside: minus the distance to the nearest face."""
    half = 0.5 * np.asarray(size, np.float64)
    closest = np.clip(p, -half, half)
    outside = np.linalg.norm(p - closest, axis=1)
    inside = np.min(half - np.abs(p), axis=1)
    return np.where(outside > 0.0, outside, -inside)


def ref_rounded_box(p, size, radius):
    """The Minkowski sum of the inner box and a ball: offset of a convex set, exact both sides."""
    inner = np.asarray(size, np.float64) - 2.0 * radius
    return ref_box(p, inner) - radius


def ref_torus(p, major_radius, minor_radius):
    """Distance to the core circle (radius R in the xz plane) minus the tube radius."""
    rho = np.hypot(p[:, 0], p[:, 2])
    safe = np.where(rho > 0.0, rho, 1.0)
    core = np.stack([p[:, 0] / safe * major_radius, np.zeros(len(p)), p[:, 2] / safe * major_radius], axis=1)
    core[rho == 0.0] = (major_radius, 0.0, 0.0)  # every core point is equidistant from the axis
    return np.linalg.norm(p - core, axis=1) - minor_radius


def ref_capsule(p, height, radius):
    """Distance to the core segment from (0, -h/2, 0) to (0, h/2, 0), minus the radius."""
    h = 0.5 * height
    y = np.clip(p[:, 1], -h, h)
    core = np.stack([np.zeros(len(p)), y, np.zeros(len(p))], axis=1)
    return np.linalg.norm(p - core, axis=1) - radius


def _meridian(p):
    return np.stack([np.hypot(p[:, 0], p[:, 2]), p[:, 1]], axis=1)


def _polygon_sdf(q, vertices):
    """Signed distance from 2D points to a convex polygon (counter-clockwise vertices)."""
    v = np.asarray(vertices, np.float64)
    dist = np.min([_seg_dist2d(q, v[i], v[(i + 1) % len(v)]) for i in range(len(v))], axis=0)
    inside = np.ones(len(q), bool)
    for i in range(len(v)):
        e = v[(i + 1) % len(v)] - v[i]
        w = q - v[i]
        inside &= (e[0] * w[:, 1] - e[1] * w[:, 0]) > 0.0
    return np.where(inside, -dist, dist)


def ref_cylinder(p, height, radius):
    """A solid of revolution: the 2D distance in the meridian plane to its profile (a rectangle)."""
    h = 0.5 * height
    return _polygon_sdf(_meridian(p), [(-radius, -h), (radius, -h), (radius, h), (-radius, h)])


def ref_cone(p, height, radius):
    """Profile: the triangle base (-r, -h/2)..(r, -h/2), apex (0, h/2)."""
    h = 0.5 * height
    return _polygon_sdf(_meridian(p), [(-radius, -h), (radius, -h), (0.0, h)])


def ref_plane(p, normal, offset):
    n = np.asarray(normal, np.float64)
    return p @ (n / np.linalg.norm(n)) - offset


REFERENCE = {
    "sphere": ref_sphere, "box": ref_box, "rounded_box": ref_rounded_box, "torus": ref_torus,
    "capsule": ref_capsule, "cylinder": ref_cylinder, "cone": ref_cone, "plane": ref_plane,
}


def _rotation(rotate) -> np.ndarray:
    """R = Rz Ry Rx from Euler degrees (extrinsic x, then y, then z), built independently of the model."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_euler("xyz", rotate, degrees=True).as_matrix()


def ref_node(n: SdfNode, p: np.ndarray) -> np.ndarray:
    """Reference distance of an SDF tree at points (N, 3), float64.

    Transforms: world = R (s q) + t. Repetition is evaluated as the minimum over explicit copies
    of the child (not by folding space into a cell, as the renderer does), so it agrees with the
    renderer only where the child fits inside its cell, as the tests arrange.
    """
    p = np.asarray(p, np.float64)
    t = n.transform
    q = (p - np.asarray(t.translate)) @ _rotation(t.rotate) / t.scale
    params = dict(n.params)
    if n.is_primitive:
        d = REFERENCE[n.kind](q, **params)
    elif n.kind == "union":
        d = np.min([ref_node(c, q) for c in n.children], axis=0)
    elif n.kind == "intersection":
        d = np.max([ref_node(c, q) for c in n.children], axis=0)
    elif n.kind == "subtraction":
        d = np.max([ref_node(n.children[0], q)] + [-ref_node(c, q) for c in n.children[1:]], axis=0)
    elif n.kind == "smooth_union":
        k = params["k"]
        d = ref_node(n.children[0], q)
        for c in n.children[1:]:
            e = ref_node(c, q)
            h = np.maximum(k - np.abs(d - e), 0.0) / k
            d = np.minimum(d, e) - h * h * k / 4.0
    elif n.kind == "repeat":
        period = np.asarray(params["period"], np.float64)
        axes = period > 0.0
        limit = params["limit"]
        if limit is not None:
            ranges = [range(-l, l + 1) if a else range(1) for l, a in zip(limit, axes)]
            cells = np.array([(i, j, k) for i in ranges[0] for j in ranges[1] for k in ranges[2]], np.float64)
            d = np.min([ref_node(n.children[0], q - period * c) for c in cells], axis=0)
        else:
            base = np.where(axes, np.round(q / np.where(axes, period, 1.0)), 0.0)
            ranges = [range(-1, 2) if a else range(1) for a in axes]
            offsets = [(i, j, k) for i in ranges[0] for j in ranges[1] for k in ranges[2]]
            d = np.min([ref_node(n.children[0], q - period * (base + np.array(o))) for o in offsets], axis=0)
    else:
        raise ValueError(n.kind)
    return d * t.scale


def ref_scene(objects, p: np.ndarray) -> np.ndarray:
    return np.min([ref_node(o, p) for o in objects], axis=0)


# --- random directions -------------------------------------------------------------------------


def random_directions(rng: np.random.Generator, n: int) -> np.ndarray:
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


# --- test kernels ------------------------------------------------------------------------------


@ti.kernel
def _distance_kernel(geo: ti.template(), pts: ti.types.ndarray(dtype=vec3, ndim=1),
                     out: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(pts.shape[0]):
        out[i] = geo.program.distance(pts[i])


def sdf(geo: SdfGeometry, pts: np.ndarray) -> np.ndarray:
    """The scene's Taichi distance at points (N, 3)."""
    pts = np.ascontiguousarray(pts, np.float32).reshape(-1, 3)
    out = np.zeros(len(pts), np.float32)
    _distance_kernel(geo, pts, out)
    return out


@ti.kernel
def _distance_material_kernel(geo: ti.template(), pts: ti.types.ndarray(dtype=vec3, ndim=1),
                              out: ti.types.ndarray(dtype=ti.math.vec2, ndim=1)):
    for i in range(pts.shape[0]):
        out[i] = geo.program.distance_material(pts[i]).xy  # (distance, material); .z is the node id


def sdf_material(geo: SdfGeometry, pts: np.ndarray):
    """The scene's Taichi distance and the material id of the nearest object, at points (N, 3)."""
    pts = np.ascontiguousarray(pts, np.float32).reshape(-1, 3)
    out = np.zeros((len(pts), 2), np.float32)
    _distance_material_kernel(geo, pts, out)
    return out[:, 0], np.rint(out[:, 1]).astype(np.int64)


# Columns of the trace kernel's outputs.
I_COLS = ("hit", "work", "front_face", "material", "trans_valid")
F_COLS = ("t", "px", "py", "pz", "nx", "ny", "nz", "nsx", "nsy", "nsz", "eps",
          "refl_ox", "refl_oy", "refl_oz", "refl_dx", "refl_dy", "refl_dz",
          "trans_ox", "trans_oy", "trans_oz", "trans_dx", "trans_dy", "trans_dz")
_FI = {name: i for i, name in enumerate(F_COLS)}
_II = {name: i for i, name in enumerate(I_COLS)}


@ti.func
def _put3(out: ti.template(), i, col: ti.template(), v):
    out[i, col] = v.x
    out[i, col + 1] = v.y
    out[i, col + 2] = v.z


@ti.kernel
def _trace_kernel(geo: ti.template(), o: ti.types.ndarray(dtype=vec3, ndim=1),
                  d: ti.types.ndarray(dtype=vec3, ndim=1), t_max: ti.f32, cone_width: ti.f32,
                  cone_spread: ti.f32, eta: ti.f32, out_i: ti.types.ndarray(dtype=ti.i32, ndim=2),
                  out_f: ti.types.ndarray(dtype=ti.f32, ndim=2)):
    # Only intersect and surface inline the SDF (compile time grows with every inlined copy);
    # spawned rays are traced by launching this kernel again on them.
    for i in range(o.shape[0]):
        ray = Ray(o=o[i], d=d[i], cone_width=cone_width, cone_spread=cone_spread)
        hit = geo.intersect(ray, t_max)
        out_i[i, _II["hit"]] = hit.hit
        out_i[i, _II["work"]] = hit.work
        out_f[i, _FI["t"]] = hit.t
        if hit.hit == 1:
            s = geo.surface(ray, hit)
            out_i[i, _II["front_face"]] = s.front_face
            out_i[i, _II["material"]] = s.material
            _put3(out_f, i, _FI["px"], s.p)
            _put3(out_f, i, _FI["nx"], s.n_geo)
            _put3(out_f, i, _FI["nsx"], s.n_shading)
            out_f[i, _FI["eps"]] = s.eps
            # Mirror reflection about the geometric normal: leaves on the side the ray came from.
            ray_r = geo.spawn(s, ray.d - 2.0 * ray.d.dot(s.n_geo) * s.n_geo)
            _put3(out_f, i, _FI["refl_ox"], ray_r.o)
            _put3(out_f, i, _FI["refl_dx"], ray_r.d)
            # Refraction through the smooth surface (eta = n_inside / n_outside).
            n_f = s.n_geo if s.front_face == 1 else -s.n_geo  # the side the ray came from
            e = eta if s.front_face == 1 else 1.0 / eta
            wo = -ray.d
            f, cos_t = mf.fresnel_dielectric(ti.min(1.0, wo.dot(n_f)), e)
            if f < 1.0:
                out_i[i, _II["trans_valid"]] = 1
                ray_t = geo.spawn(s, ti.math.normalize(mf.refract(wo, n_f, e, cos_t)))
                _put3(out_f, i, _FI["trans_ox"], ray_t.o)
                _put3(out_f, i, _FI["trans_dx"], ray_t.d)


class TraceResult:
    """Columns of one trace batch by name: r.t, r.hit, r.p (N,3), r.n, r.refl_o ..."""

    def __init__(self, o, d, out_i, out_f, t_max, cone_width, cone_spread):
        self.o = o.astype(np.float64)
        self.d = d.astype(np.float64)
        self._i = out_i
        self._f = out_f
        self.t_max = t_max
        self.cone_width = cone_width
        self.cone_spread = cone_spread

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        if name in _II:
            return self._i[:, _II[name]]
        if name in _FI:
            return self._f[:, _FI[name]].astype(np.float64)
        vectors = {"p": "px", "n": "nx", "n_shading": "nsx", "refl_o": "refl_ox", "refl_d": "refl_dx",
                   "trans_o": "trans_ox", "trans_d": "trans_dx"}
        if name in vectors:
            c = _FI[vectors[name]]
            return self._f[:, c:c + 3].astype(np.float64)
        raise AttributeError(name)

    def __len__(self):
        return len(self.o)


def trace(geo: SdfGeometry, o, d, t_max: float, cone_width: float = 0.0, cone_spread: float = 0.0,
          eta: float = 1.5) -> TraceResult:
    """Intersect; on a hit, shade and spawn a mirror-reflected and a refracted ray (not traced here:
    pass r.refl_o, r.refl_d to trace again)."""
    o = np.ascontiguousarray(o, np.float32).reshape(-1, 3)
    d = np.ascontiguousarray(d, np.float32).reshape(-1, 3)
    out_i = np.zeros((len(o), len(I_COLS)), np.int32)
    out_f = np.zeros((len(o), len(F_COLS)), np.float32)
    _trace_kernel(geo, o, d, t_max, cone_width, cone_spread, eta, out_i, out_f)
    return TraceResult(o, d, out_i, out_f, t_max, cone_width, cone_spread)


@ti.kernel
def _segment_kernel(geo: ti.template(), o: ti.types.ndarray(dtype=vec3, ndim=1),
                    d: ti.types.ndarray(dtype=vec3, ndim=1), length: ti.types.ndarray(dtype=ti.f32, ndim=1),
                    coarse: ti.i32, fine: ti.f32, out: ti.types.ndarray(dtype=ti.f32, ndim=2)):
    for i in range(o.shape[0]):
        side = 1.0 if geo.program.distance(o[i]) >= 0.0 else -1.0
        a = side * geo.program.distance(o[i])
        crossing = -1.0
        unresolved = 0
        lowest = a
        if length[i] > 0.0:
            dt = length[i] / coarse
            for j in range(1, coarse + 1):
                s = j * dt
                b = side * geo.program.distance(o[i] + s * d[i])
                lowest = ti.min(lowest, b)
                if b < 0.0:
                    crossing = s
                    break
                if a + b <= dt:
                    # Not certified by the Lipschitz bound: the unbounding spheres of the two samples
                    # leave a gap in which a surface could hide. Resample that interval finely.
                    m = ti.max(1, ti.cast(ti.ceil(dt / fine), ti.i32))
                    sub = dt / m
                    aa = a
                    for k in range(1, m + 1):
                        ss = s - dt + k * sub
                        bb = side * geo.program.distance(o[i] + ss * d[i])
                        lowest = ti.min(lowest, bb)
                        if bb < 0.0:
                            crossing = ss
                            break
                        if aa + bb <= sub:
                            unresolved += 1
                        aa = bb
                    if crossing >= 0.0:
                        break
                a = b
        out[i, 0] = crossing
        out[i, 1] = unresolved
        out[i, 2] = lowest


def first_crossing(geo: SdfGeometry, o, d, length, coarse: int, fine: float):
    """Check the segments o + s d, s in [0, length], for a change of the SDF's sign from the origin's.

    Samples `coarse` points evenly; where two neighbours' distances a, b satisfy a + b <= spacing
    (their unbounding spheres do not cover the interval, so a thin solid could fit in between), the
    interval is resampled at spacing <= `fine`. With a Lipschitz-1 SDF a crossed solid whose chord
    along the ray is longer than `fine` always puts a sample on the far side of the origin's sign;
    a shorter one leaves an interval uncertified even at the fine spacing, counted as "unresolved"
    (the segment passes within fine/2 of a surface there).

    Returns (crossing s or -1, unresolved interval count, lowest origin-side distance seen).
    """
    o = np.ascontiguousarray(o, np.float32).reshape(-1, 3)
    d = np.ascontiguousarray(d, np.float32).reshape(-1, 3)
    length = np.ascontiguousarray(length, np.float32).reshape(-1)
    out = np.zeros((len(o), 3), np.float32)
    _segment_kernel(geo, o, d, length, coarse, fine, out)
    return out[:, 0].astype(np.float64), out[:, 1].astype(np.int64), out[:, 2].astype(np.float64)


@ti.kernel
def _normal_kernel(geo: ti.template(), p: ti.types.ndarray(dtype=vec3, ndim=1), h: ti.f32,
                   out: ti.types.ndarray(dtype=vec3, ndim=1)):
    for i in range(p.shape[0]):
        n, _ = geo.normal_and_material(p[i], h)
        out[i] = n


def normals(geo: SdfGeometry, p, h: float) -> np.ndarray:
    p = np.ascontiguousarray(p, np.float32).reshape(-1, 3)
    out = np.zeros_like(p)
    _normal_kernel(geo, p, h, out)
    return out.astype(np.float64)


@ti.kernel
def _intersect_kernel(geo: ti.template(), o: ti.types.ndarray(dtype=vec3, ndim=1),
                      d: ti.types.ndarray(dtype=vec3, ndim=1), t_max: ti.f32, cone_width: ti.f32,
                      cone_spread: ti.f32, out_i: ti.types.ndarray(dtype=ti.i32, ndim=2),
                      out_t: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(o.shape[0]):
        hit = geo.intersect(Ray(o=o[i], d=d[i], cone_width=cone_width, cone_spread=cone_spread), t_max)
        out_i[i, 0] = hit.hit
        out_i[i, 1] = hit.work
        out_t[i] = hit.t


def intersect(geo: SdfGeometry, o, d, t_max: float, cone_width: float = 0.0, cone_spread: float = 0.0):
    """Only the intersection: (hit, work, t) arrays. Compiles a single inlined copy of the SDF."""
    o = np.ascontiguousarray(o, np.float32).reshape(-1, 3)
    d = np.ascontiguousarray(d, np.float32).reshape(-1, 3)
    out_i = np.zeros((len(o), 2), np.int32)
    out_t = np.zeros(len(o), np.float32)
    _intersect_kernel(geo, o, d, t_max, cone_width, cone_spread, out_i, out_t)
    return out_i[:, 0], out_i[:, 1], out_t.astype(np.float64)


__all__ = ["PRIMITIVES", "PRIMITIVE_PARAMS", "node", "make_scene", "make_geometry", "set_march", "ref_node",
           "ref_scene", "random_directions", "sdf", "sdf_material", "trace", "TraceResult", "first_crossing",
           "normals", "intersect"]

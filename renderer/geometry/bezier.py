"""Surfaces of revolution of Bezier profiles, numpy side: profile checks, cubic segments, patches
with their bounding boxes, and exact evaluation (for shading tests and tessellation).

The profile is a 2D curve (radius, height) in the object's frame, made of Bezier segments of one
degree (1 to 3) that share end points; it is revolved about the local y axis:

    S(u, phi) = (r(u) cos phi, h(u), r(u) sin phi),   u in [0, 1] per segment, phi in [0, 2 pi].

Every segment is stored as a cubic (lower degrees are raised exactly), so the device evaluates one
kind of curve. Orientation: S_u x S_phi = r (h' cos phi, -r', h' sin phi), which points away from
the axis where the profile climbs (h' > 0). A closed profile listed counter-clockwise in the
(radius, height) plane (up the outside, back down the inside) therefore has outward normals.

Patches are the BVH primitives: a u-span of one segment times an angular sector. Spans are split
until the profile's tangent turns by at most MAX_TURN degrees within each, so that (with sectors of
at most 360/sectors degrees) every patch is nearly flat and a ray meets it at most once except
near tangency, which is what lets a Newton start inside the patch's box find the first root.
"""
from __future__ import annotations

import math

import numpy as np

MAX_DEGREE = 3
MAX_TURN = math.radians(30.0)  # most the profile's tangent may turn within one patch
MAX_SPLIT_DEPTH = 6  # halvings of a span to meet MAX_TURN; a cusp never meets it, so bound the work
# Relative padding of patch boxes: the device computes the ray in the object frame in f32, so a
# box must contain its surface with a margin of a few float32 ulps of the object's size.
BOX_PAD = 1e-5


# --- checking a profile ----------------------------------------------------------------------


def profile_problem(points, degree: int) -> str | None:
    """What is wrong with a profile, as one sentence, or None. points: (N, 2) radius, height."""
    if degree not in range(1, MAX_DEGREE + 1):
        return f"degree {degree} is not supported (1 to {MAX_DEGREE})"
    n = len(points)
    if n < 2:
        return f"profile needs at least 2 points, got {n}"
    if (n - 1) % degree:
        examples = ", ".join(str(degree * k + 1) for k in (1, 2, 3))
        return (f"profile has {n} points; a degree-{degree} profile needs {degree}k + 1 points "
                f"({examples}, ...)")
    p = np.asarray(points, np.float64)
    if not np.isfinite(p).all():
        return "profile has a value that is not a finite number"
    negative = np.flatnonzero(p[:, 0] < 0.0)
    if len(negative):
        i = int(negative[0])
        return f"profile[{i}] has a negative radius {p[i, 0]:g} (radii must be >= 0)"
    for s in range((n - 1) // degree):
        seg = p[s * degree:s * degree + degree + 1]
        if np.all(seg == seg[0]):
            return f"profile segment {s} (points {s * degree} to {s * degree + degree}) is a single point"
        if np.all(seg[:, 0] == 0.0):
            return f"profile segment {s} lies on the axis (radius 0 throughout), which is no surface"
    return None


# --- curves ------------------------------------------------------------------------------------


def elevate(ctrl: np.ndarray) -> np.ndarray:
    """The same curve with one more control point (exact degree elevation)."""
    n = len(ctrl) - 1
    out = np.empty((n + 2, ctrl.shape[1]))
    out[0], out[-1] = ctrl[0], ctrl[-1]
    for i in range(1, n + 1):
        a = i / (n + 1)
        out[i] = a * ctrl[i - 1] + (1.0 - a) * ctrl[i]
    return out


def cubic_segments(points, degree: int) -> np.ndarray:
    """(S, 4, 2) cubic control points, one row per segment of the profile."""
    p = np.asarray(points, np.float64)
    segments = []
    for s in range((len(p) - 1) // degree):
        seg = p[s * degree:s * degree + degree + 1]
        while len(seg) < 4:
            seg = elevate(seg)
        segments.append(seg)
    return np.array(segments).reshape(-1, 4, 2)


def bernstein(u):
    """Cubic Bernstein basis and its derivative, (..., 4) each."""
    u = np.asarray(u, np.float64)
    s = 1.0 - u
    b = np.stack([s ** 3, 3 * s * s * u, 3 * s * u * u, u ** 3], axis=-1)
    db = np.stack([-3 * s * s, 3 * s * s - 6 * s * u, 6 * s * u - 3 * u * u, 3 * u * u], axis=-1)
    return b, db


def curve_point(ctrl: np.ndarray, u):
    """Point (..., 2) and derivative (..., 2) of cubics ctrl (..., 4, 2) at u (broadcast)."""
    b, db = bernstein(u)
    return np.einsum("...i,...ij->...j", b, ctrl), np.einsum("...i,...ij->...j", db, ctrl)


def sub_curve(ctrl: np.ndarray, a: float, b: float) -> np.ndarray:
    """Control points of the span [a, b] of one cubic (two de Casteljau cuts)."""

    def split(c, t):
        levels = [c]
        while len(levels[-1]) > 1:
            prev = levels[-1]
            levels.append((1 - t) * prev[:-1] + t * prev[1:])
        return np.array([lv[0] for lv in levels]), np.array([lv[-1] for lv in reversed(levels)])

    _, right = split(np.asarray(ctrl, np.float64), a)
    if b >= 1.0:
        return right
    left, _ = split(right, (b - a) / (1.0 - a) if a < 1.0 else 0.0)
    return left


def tangent_spread(ctrl: np.ndarray) -> float:
    """Largest angle between the hodograph's control vectors: bounds how far the tangent turns."""
    v = np.diff(ctrl, axis=0)
    length = np.linalg.norm(v, axis=1)
    v = v[length > 1e-12 * max(1.0, np.abs(ctrl).max())]
    if len(v) < 2:
        return 0.0
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    return float(np.arccos(np.clip(v @ v.T, -1.0, 1.0)).max())


def spans_of(ctrl: np.ndarray, spans: int) -> list[tuple[float, float]]:
    """u-spans of one segment: `spans` equal ones, halved until each turns by <= MAX_TURN."""
    out = []
    stack = [(k / spans, (k + 1) / spans, 0) for k in reversed(range(spans))]
    while stack:
        a, b, depth = stack.pop()
        if depth < MAX_SPLIT_DEPTH and tangent_spread(sub_curve(ctrl, a, b)) > MAX_TURN:
            m = 0.5 * (a + b)
            stack += [(m, b, depth + 1), (a, m, depth + 1)]
        else:
            out.append((a, b))
    return out


# --- patches -------------------------------------------------------------------------------------


def _sector_extent(rmin, rmax, f0, f1, trig):
    """Range of r * trig(phi) over r in [rmin, rmax] (r >= 0) and phi in [f0, f1]."""
    phis = [f0, f1] + [k * math.pi / 2 for k in range(5) if f0 < k * math.pi / 2 < f1]
    values = [trig(f) for f in phis]
    lo, hi = min(values), max(values)
    return min(rmin * lo, rmax * lo), max(rmin * hi, rmax * hi)


def patch_table(cubics: np.ndarray, spans: int, sectors: int) -> dict:
    """The patches of one object: curve index, (u0, u1, phi0, phi1) and the object-space box
    (control-polygon hull of the span, swept over the sector), padded by BOX_PAD of the size."""
    size = max(float(np.abs(cubics).max()), 1e-30)
    pad = BOX_PAD * size
    curve, ranges, boxes = [], [], []
    for c, ctrl in enumerate(cubics):
        for a, b in spans_of(ctrl, spans):
            hull = sub_curve(ctrl, a, b)
            rmin, rmax = hull[:, 0].min(), hull[:, 0].max()
            hmin, hmax = hull[:, 1].min(), hull[:, 1].max()
            rmin = max(rmin, 0.0)
            for k in range(sectors):
                f0, f1 = 2 * math.pi * k / sectors, 2 * math.pi * (k + 1) / sectors
                x = _sector_extent(rmin, rmax, f0, f1, math.cos)
                z = _sector_extent(rmin, rmax, f0, f1, math.sin)
                curve.append(c)
                ranges.append((a, b, f0, f1))
                boxes.append(((x[0] - pad, hmin - pad, z[0] - pad), (x[1] + pad, hmax + pad, z[1] + pad)))
    return {"curve": np.array(curve, np.int32), "range": np.array(ranges, np.float64).reshape(-1, 4),
            "box": np.array(boxes, np.float64).reshape(-1, 2, 3)}


def world_boxes(box: np.ndarray, matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World AABBs (lo, hi) of object-space boxes (N, 2, 3) under the 3x4 (or 4x4) matrix."""
    corners = np.stack(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij"), axis=-1).reshape(8, 3)
    pts = np.stack([box[:, corners[:, i], i] for i in range(3)], axis=-1)  # (N, 8, 3)
    world = pts @ matrix[:3, :3].T + matrix[:3, 3]
    lo, hi = world.min(axis=1), world.max(axis=1)
    pad = 1e-6 * np.maximum(np.abs(lo), np.abs(hi)).max(axis=1, keepdims=True)  # f32 rounding margin
    return lo - pad, hi + pad


# --- evaluation ------------------------------------------------------------------------------------


def surface_point(ctrl: np.ndarray, u, phi):
    """Object-space S, S_u and S_phi of cubics ctrl (..., 4, 2) at (u, phi) (float64)."""
    (r, h), (dr, dh) = (np.moveaxis(a, -1, 0) for a in curve_point(ctrl, u))
    r, h, dr, dh, c, s = np.broadcast_arrays(r, h, dr, dh, np.cos(phi), np.sin(phi))
    S = np.stack([r * c, h, r * s], axis=-1)
    Su = np.stack([dr * c, dh, dr * s], axis=-1)
    Sp = np.stack([-r * s, np.zeros_like(r), r * c], axis=-1)
    return S, Su, Sp


def tessellate(cubics: np.ndarray, matrix: np.ndarray, u_steps: int, sectors: int) -> np.ndarray:
    """(T, 3, 3) world triangles with vertices on the surface: a grid of u_steps per segment times
    `sectors` angles (an inscribed approximation, for reference intersections in tests)."""
    u = np.linspace(0.0, 1.0, u_steps + 1)
    phi = np.linspace(0.0, 2 * np.pi, sectors + 1)
    tris = []
    for ctrl in cubics:
        S, _, _ = surface_point(ctrl[None, None], u[:, None], phi[None, :])  # (U+1, F+1, 3)
        W = S @ matrix[:3, :3].T + matrix[:3, 3]
        a, b, c, d = W[:-1, :-1], W[1:, :-1], W[1:, 1:], W[:-1, 1:]
        tris.append(np.stack([a, b, c], axis=2).reshape(-1, 3, 3))
        tris.append(np.stack([a, c, d], axis=2).reshape(-1, 3, 3))
    return np.concatenate(tris)


# --- mesh data ---------------------------------------------------------------------------------------


def bezier_fields(objects) -> dict:
    """MeshData's bezier_* arrays for objects given as (cubics (S, 4, 2), object-to-world matrix
    (4x4 or 3x4), material id, spans, sectors). Texture u runs over [0, 1] along the whole profile,
    one equal share per segment."""
    curves, curve_object, curve_u, matrices = [], [], [], []
    patches, patch_curve, boxes, materials = [], [], [], []
    for index, (cubics, matrix, material, spans, sectors) in enumerate(objects):
        table = patch_table(cubics, spans, sectors)
        first = len(curves)
        curves.extend(cubics)
        n = len(cubics)
        curve_object += [index] * n
        curve_u += [(k / n, 1.0 / n) for k in range(n)]
        matrices.append(np.asarray(matrix, np.float64)[:3, :4])
        patches.append(table["range"])
        patch_curve.append(table["curve"] + first)
        boxes.append(table["box"])
        materials.append(np.full(len(table["curve"]), material, np.int32))
    if not objects:
        return {}
    return {"bezier_curves": np.array(curves, np.float32).reshape(-1, 4, 2),
            "bezier_curve_object": np.array(curve_object, np.int32),
            "bezier_curve_u": np.array(curve_u, np.float32).reshape(-1, 2),
            "bezier_objects": np.array(matrices, np.float32).reshape(-1, 3, 4),
            "bezier_patches": np.concatenate(patches).astype(np.float32),
            "bezier_patch_curve": np.concatenate(patch_curve).astype(np.int32),
            "bezier_patch_box": np.concatenate(boxes).astype(np.float32),
            "bezier_material": np.concatenate(materials)}

"""Ray/primitive intersection for the mesh world: triangles (watertight and Moller-Trumbore),
spheres, quads and discs, plus ray/box slabs. Every function returns hit flags and parametric
distances in (0, t_max); none relies on an epsilon for correctness, since spawned rays are
offset by `offset_ray_origin` instead.
"""
import numpy as np
import taichi as ti

vec3 = ti.math.vec3


@ti.func
def watertight_setup(d):
    """Per-ray constants of Woop, Benthin and Wald 2013: the axis permutation (kx, ky, kz) putting
    the largest |d| component last (swapping kx, ky when it is negative keeps the winding) and
    the shear S mapping the ray onto +z."""
    ad = ti.abs(d)
    kz = 2
    if ad.x >= ad.y and ad.x >= ad.z:
        kz = 0
    elif ad.y >= ad.z:
        kz = 1
    kx = (kz + 1) % 3
    ky = (kx + 1) % 3
    if d[kz] < 0.0:
        swap = kx
        kx = ky
        ky = swap
    s = vec3(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz])
    return ti.math.ivec3(kx, ky, kz), s


@ti.func
def triangle_watertight(o, k, s, v0, v1, v2, t_max):
    """Watertight ray/triangle test: edge functions on sheared, translated vertices are exact in
    sign for points on shared edges, so no ray passes between two triangles sharing an edge.
    Returns (hit, t, b1, b2) with barycentrics of v1, v2. (The paper's f64 fallback for edge
    functions that are exactly 0 is omitted: f64 is not available on every GPU back-end; a zero
    edge function counts as inside, which can only make an edge hit twice, never zero times.)"""
    a = v0 - o
    b = v1 - o
    c = v2 - o
    ax = a[k.x] - s.x * a[k.z]
    ay = a[k.y] - s.y * a[k.z]
    bx = b[k.x] - s.x * b[k.z]
    by = b[k.y] - s.y * b[k.z]
    cx = c[k.x] - s.x * c[k.z]
    cy = c[k.y] - s.y * c[k.z]
    u = cx * by - cy * bx
    v = ax * cy - ay * cx
    w = bx * ay - by * ax
    hit = 0
    t = 0.0
    b1 = 0.0
    b2 = 0.0
    if not ((u < 0.0 or v < 0.0 or w < 0.0) and (u > 0.0 or v > 0.0 or w > 0.0)):
        det = u + v + w
        if det != 0.0:
            az = s.z * a[k.z]
            bz = s.z * b[k.z]
            cz = s.z * c[k.z]
            tt = u * az + v * bz + w * cz
            # A back face (det < 0) has u, v, w, tt all of det's sign: compare |tt| against
            # |det| for the range, and divide by the signed det so both t and the barycentrics
            # come out positive (flipping only tt and det once left b1, b2 negated).
            sign = 1.0 if det > 0.0 else -1.0
            if tt * sign > 0.0 and tt * sign < t_max * det * sign:
                inv = 1.0 / det
                hit = 1
                t = tt * inv
                b1 = v * inv
                b2 = w * inv
    return hit, t, b1, b2


@ti.func
def triangle_moller_trumbore(o, d, v0, v1, v2, t_max):
    """Moller and Trumbore 1997: fewer operations, but not watertight at shared edges."""
    e1 = v1 - v0
    e2 = v2 - v0
    p = d.cross(e2)
    det = e1.dot(p)
    hit = 0
    t = 0.0
    b1 = 0.0
    b2 = 0.0
    if det != 0.0:
        inv = 1.0 / det
        tv = o - v0
        u = tv.dot(p) * inv
        q = tv.cross(e1)
        v = d.dot(q) * inv
        tt = e2.dot(q) * inv
        if u >= 0.0 and v >= 0.0 and u + v <= 1.0 and tt > 0.0 and tt < t_max:
            hit = 1
            t = tt
            b1 = u
            b2 = v
    return hit, t, b1, b2


@ti.func
def sphere(o, d, center, radius, t_max):
    """Ray/sphere with the precision-preserving form of Haines et al. 2019 (Ray Tracing Gems 7):
    the discriminant from the closest-approach vector, the near root from the stable quotient.
    d must be unit length. Returns (hit, t)."""
    f = o - center
    b = -f.dot(d)
    l = f + b * d
    disc = radius * radius - l.dot(l)
    hit = 0
    t = 0.0
    if disc >= 0.0:
        c = f.dot(f) - radius * radius
        q = b + ti.math.sign(b) * ti.sqrt(disc) if b != 0.0 else ti.sqrt(disc)
        t0 = c / q if q != 0.0 else 0.0
        t1 = q
        near = ti.min(t0, t1)
        far = ti.max(t0, t1)
        if near > 0.0 and near < t_max:
            hit = 1
            t = near
        elif far > 0.0 and far < t_max:
            hit = 1
            t = far
    return hit, t


@ti.func
def sphere_uv(x, y, z):
    """A sphere's texture coordinates at the unit direction (x, y, z) from its centre in its own
    frame, as Mitsuba's sphere has them: (the angle about z from x towards y in [0, 2 pi), the
    angle from z) scaled to [0, 1]."""
    phi = ti.atan2(y, x)
    if phi < 0.0:
        phi += 2.0 * np.pi
    return ti.math.vec2(phi / (2.0 * np.pi), ti.acos(ti.math.clamp(z, -1.0, 1.0)) / np.pi)


# Unit roundoff of float32, 2^-24.
F32_UNIT_ROUNDOFF = 5.9604645e-08
# A primitive's spawn clearance in roundoffs of the magnitude its points are computed at
# (spawn_clearance).
CLEARANCE_ROUNDOFFS = 8.0


@ti.func
def max_abs(v):
    return ti.max(ti.abs(v.x), ti.max(ti.abs(v.y), ti.abs(v.z)))


@ti.func
def spawn_clearance(scale):
    """How far a ray leaving a primitive must start off it so that the primitive's own test cannot
    find it again at the origin, for a surface point computed from coordinates of magnitude
    `scale` (a sphere's |centre| + radius, a triangle's largest corner, a quad's corner and
    edges). offset_ray_origin moves a point by ulps of its own magnitude, which is enough where
    the point is as large as the coordinates it came from; a point near the origin on a large
    primitive is not: the weekend scene's ground (a sphere of radius 1000 about (0, -1000, 0))
    has points near y = 0 whose errors are ~1e-4 against an offset of 1.5e-5, and so does a
    tilted ground quad or triangle a kilometre across near its middle. The point rounds at a few
    roundoffs of `scale` (pbrt: gamma(5) |p| for a sphere in object space, gamma(7) sum |b_i v_i|
    for a triangle), and so does each test's inside/outside decision (the sphere's
    |o - centre|^2 - radius^2, the triangle's t); 8 of them: 0.95 mm for that ground, 1e-6 of a
    unit object at the origin."""
    return CLEARANCE_ROUNDOFFS * F32_UNIT_ROUNDOFF * scale


@ti.func
def quad(o, d, corner, edge_u, edge_v, t_max):
    """Parallelogram corner + a edge_u + b edge_v, a, b in [0, 1]. Returns (hit, t, a, b).
    The plane's rows (quad_frames) computed in the kernel; leaves read them precomputed."""
    n = edge_u.cross(edge_v)
    nn = n.dot(n)
    return quad_framed(o, d, corner, n, edge_v.cross(n) / nn, n.cross(edge_u) / nn, t_max)


def quad_frames(quads: np.ndarray) -> np.ndarray:
    """(n, 3, 3) float32 rows (normal, u_dual, v_dual) of quads given as (corner, edge_u, edge_v):
    normal = edge_u x edge_v, and the dual vectors with p . u_dual = a, p . v_dual = b for every
    p = a edge_u + b edge_v in the quad's plane, so that `quad_framed` needs no cross product and
    one division. Computed in float64: they are exact to float32 rounding."""
    q = np.asarray(quads, dtype=np.float64).reshape(-1, 3, 3)
    n = np.cross(q[:, 1], q[:, 2])
    nn = np.maximum(np.einsum("ij,ij->i", n, n), 1e-300)[:, None]
    u_dual = np.cross(q[:, 2], n) / nn
    v_dual = np.cross(n, q[:, 1]) / nn
    return np.stack([n, u_dual, v_dual], axis=1).astype(np.float32)


@ti.func
def quad_framed(o, d, corner, normal, u_dual, v_dual, t_max):
    """`quad` with the plane's precomputed rows of quad_frames: the same hits and coordinates to
    float32 rounding, at a third of the arithmetic (the leaf test of quads)."""
    denom = normal.dot(d)
    hit = 0
    t = 0.0
    a = 0.0
    b = 0.0
    if denom != 0.0:
        tt = normal.dot(corner - o) / denom
        if tt > 0.0 and tt < t_max:
            p = o + tt * d - corner
            a = p.dot(u_dual)
            b = p.dot(v_dual)
            if a >= 0.0 and a <= 1.0 and b >= 0.0 and b <= 1.0:
                hit = 1
                t = tt
    return hit, t, a, b


@ti.func
def disc(o, d, center, normal, radius, t_max):
    denom = normal.dot(d)
    hit = 0
    t = 0.0
    if denom != 0.0:
        tt = normal.dot(center - o) / denom
        if tt > 0.0 and tt < t_max:
            p = o + tt * d - center
            if p.dot(p) <= radius * radius:
                hit = 1
                t = tt
    return hit, t


# Returned by box_entry on a miss: above every t_max the renderer uses (INF = 1e30), so a missed
# box can never compare as nearer than the closest hit (t_max + 1 would round to t_max at 1e30).
BOX_MISS = 3.0e38


@ti.func
def box_entry(o, inv_d, lo, hi, t_max):
    """Slab test. Returns the entry distance, or BOX_MISS on a miss.
    The far bound is widened by 2 ulp-scale factors so rounding never drops a box a ray grazes
    (Ize 2013, 'Robust BVH ray traversal')."""
    t0 = (lo - o) * inv_d
    t1 = (hi - o) * inv_d
    tmin = ti.min(t0, t1)
    tmax = ti.max(t0, t1)
    enter = ti.max(ti.max(tmin.x, tmin.y), ti.max(tmin.z, 0.0))
    leave = ti.min(ti.min(tmax.x, tmax.y), ti.min(tmax.z, t_max)) * 1.00000024
    return enter if enter <= leave else BOX_MISS


@ti.func
def offset_ray_origin(p, n):
    """Waechter and Binder 2019 (Ray Tracing Gems 6): move p off its surface along n by a few
    ulps of p's own magnitude (integer steps on the float bit pattern), or by a small fixed
    amount near the origin where ulps are tiny. Scale-aware: works from 1e-3 to 1e4 metres."""
    of_i = ti.cast(256.0 * n, ti.i32)  # 256 ulps per unit of normal
    result = p
    for i in ti.static(range(3)):
        pi = ti.bit_cast(ti.bit_cast(p[i], ti.i32) + (-of_i[i] if p[i] < 0.0 else of_i[i]), ti.f32)
        result[i] = p[i] + (1.0 / 65536.0) * n[i] if ti.abs(p[i]) < (1.0 / 32.0) else pi
    return result

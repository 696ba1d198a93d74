"""Float32 error bounds of ray/triangle hits, exact (float64) answers to hold them against, and the
random directions the hit-point tests aim along.

The bound: a triangle test run in f32 returns t and barycentrics b1, b2 whose points o + t d and
b0 v0 + b1 v1 + b2 v2 (each evaluated exactly from the f32 results) lie within

    TOL = 128 u (t + L) kappa / cos

of the exact intersection of the same f32 ray and triangle; u = 2^-24 is f32's unit roundoff,
L the longest edge, kappa = L^2 / (2 area) >= 2/sqrt(3) the shape's conditioning (large for
slivers), cos = |d . n| the cosine of incidence. First-order counts with every rounding taken
against us (real errors sit far below):

- Moller-Trumbore: tv = o - v0 rounds by u (t + L); p = d x e2 and q = tv x e1 by 2u of their
  factors, the dot products by 3u; so tv . p and d . q are off by 6u (t + L) L and
  det = e1 . p = 2 area cos by 5u L^2: each barycentric by 11u (t + L) kappa / (L cos), the
  point by 22u (t + L) kappa / cos, t = e2 . q / det by 11u (t + L) kappa / cos.
- Watertight (Woop et al. 2013): translating and shearing rounds each vertex's sheared
  coordinates by e <= 7u (t + L), i.e. moves the vertices; the barycentric point of a fixed
  ray then moves by at most e in the sheared plane (a convex combination of the moves), 2e / cos
  on the triangle: 14u (t + L) / cos. The edge functions' products (sheared coordinates are at
  most sqrt(2) L, the ray passing through the triangle) round by 6u L^2 each, det by 18u L^2:
  b1, b2 by 24u kappa / cos each, the point by 48u kappa L / cos, and t (a depth read through
  1 / |d_kz| <= sqrt(3)) by sqrt(3) times that, 83u kappa L / cos; depths and tt add
  (4 sqrt(3) + 1) u (t + L). Totals: point 62, t 98 (in units of u (t + L) kappa / cos).
128 covers the largest count with room for the second-order terms the counts leave out.
"""
import numpy as np

U = 2.0 ** -24  # f32 unit roundoff
TRIANGLE_CONSTANT = 128.0  # the docstring's counts: at most 98


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def interior_barycentrics(rng, n, margin=0.02):
    """(n, 3) random barycentrics, each at least `margin`: points inside a triangle, off its edges."""
    return margin + (1.0 - 3.0 * margin) * rng.dirichlet((1.0, 1.0, 1.0), n)


def tilted(rng, normal, min_cosine):
    """Unit vectors w with w . normal uniform in [min_cosine, 1] and a uniform azimuth about each
    unit normal (N, 3)."""
    cosine = rng.uniform(min_cosine, 1.0, len(normal))
    across = unit(np.cross(normal, rng.normal(size=normal.shape)))
    return cosine[:, None] * normal + np.sqrt(1.0 - cosine ** 2)[:, None] * across


def triangle_shape(v):
    """Longest edge L, conditioning kappa = L^2 / (2 area) and unit normal (e1 x e2) of
    triangles v (N, 3 corners, xyz), float64."""
    v = np.asarray(v, np.float64)
    e1, e2, e3 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0], v[:, 2] - v[:, 1]
    cross = np.cross(e1, e2)
    twice_area = np.linalg.norm(cross, axis=1)
    longest = np.max([np.linalg.norm(e, axis=1) for e in (e1, e2, e3)], axis=0)
    return longest, longest ** 2 / twice_area, cross / twice_area[:, None]


def triangle_tolerance(t, longest, kappa, cosine):
    """TOL of the module docstring: how far an f32 hit point may lie from the exact one."""
    return TRIANGLE_CONSTANT * U * (np.asarray(t) + longest) * kappa / np.abs(cosine)


def exact_triangle_hit(o, d, v):
    """(t, b1, b2) of rays o + t d against the plane of triangles v, by Cramer's rule in float64
    on the f32 inputs as given (no clipping to the triangle, no side test)."""
    o, d, v = (np.asarray(x, np.float64) for x in (o, d, v))
    e1, e2, tv = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0], o - v[:, 0]
    p = np.cross(d, e2)
    q = np.cross(tv, e1)
    det = (e1 * p).sum(axis=1)
    return (e2 * q).sum(axis=1) / det, (tv * p).sum(axis=1) / det, (d * q).sum(axis=1) / det


def _segment_distance(p, a, b):
    ab = b - a
    s = np.clip(((p - a) * ab).sum(axis=1) / (ab * ab).sum(axis=1), 0.0, 1.0)
    return np.linalg.norm(p - (a + s[:, None] * ab), axis=1)


def point_triangle_distance(p, v):
    """Distance (float64) from points p (N, 3) to the solid triangles v (N, 3, 3): to the plane where
    the foot of p lies inside the triangle, else to the nearest edge."""
    p, v = np.asarray(p, np.float64), np.asarray(v, np.float64)
    _, _, normal = triangle_shape(v)
    height = ((p - v[:, 0]) * normal).sum(axis=1)
    foot = p - height[:, None] * normal
    inside = np.ones(len(p), bool)
    for i in range(3):
        a, b = v[:, i], v[:, (i + 1) % 3]
        inside &= (np.cross(b - a, foot - a) * normal).sum(axis=1) >= 0.0
    edges = np.min([_segment_distance(p, v[:, i], v[:, (i + 1) % 3]) for i in range(3)], axis=0)
    return np.where(inside, np.abs(height), edges)

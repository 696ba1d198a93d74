"""The shading normal a packet's lanes shade with, as the scalar path has it: a triangle's vertex
normals interpolated at the hit (MeshGeometry.surface), made consistent with the geometric normal
and the viewer (geometry.shading.consistent_shading_normal), and pbrt's rule that a direction
the shading normal and the true surface put on different sides is no reflection
(materials/bsdf.py, `_sides_agree`).

With these in lanes, a world with vertex normals keeps its Lambert lanes in lane arithmetic and
hands its other lanes to the scalar BSDF with a plain record; before, every lane of such a world
took the geometry's whole surface record and the scalar BSDF one after another.
"""
import taichi as ti

from renderer.geometry.shading import MIN_SHADING_COSINE
from renderer.packets.lanes import dot, mask, normalized


@ti.func
def interpolated_normals(geometry: ti.template(), prim, b1, b2, nx, ny, nz):
    """Lanes of the normal before it is made consistent: a triangle's vertex normals mixed by the
    hit's barycentrics (b1, b2) and normalised, or where the mix has no length, or the primitive
    is not a triangle, the unit geometric normal n. geometry: a MeshGeometry with vertex normals."""
    triangles = geometry.range_end[0]
    b0 = 1.0 - b1 - b2
    mx, my, mz = nx * 0.0, nx * 0.0, nx * 0.0
    for k in ti.static(range(prim.n)):
        g = ti.min(ti.max(prim[k], 0), ti.max(triangles - 1, 0))
        mixed = b0[k] * geometry.tri_n[g, 0] + b1[k] * geometry.tri_n[g, 1] + b2[k] * geometry.tri_n[g, 2]
        mx[k], my[k], mz[k] = mixed.x, mixed.y, mixed.z
    length2 = mx * mx + my * my + mz * mz
    use = (prim >= 0) & (prim < triangles) & (length2 > 1e-12)
    inv = 1.0 / ti.sqrt(ti.select(use, length2, 1.0))
    return ti.select(use, mx * inv, nx), ti.select(use, my * inv, ny), ti.select(use, mz * inv, nz)


@ti.func
def consistent_normals(sx, sy, sz, nx, ny, nz, wx, wy, wz):
    """consistent_shading_normal(s, n, w) lane by lane: s turned to n's side, then, where the
    viewer direction w sees it at a cosine below MIN_SHADING_COSINE, bent towards w just enough."""
    turn = ti.select(dot(sx, sy, sz, nx, ny, nz) < 0.0, -1.0, 1.0)
    sx, sy, sz = turn * sx, turn * sy, turn * sz
    side = ti.select(dot(wx, wy, wz, nx, ny, nz) >= 0.0, 1.0, -1.0)
    c = side * dot(sx, sy, sz, wx, wy, wz)
    push = side * (MIN_SHADING_COSINE - c)
    bx, by, bz = normalized(sx + push * wx, sy + push * wy, sz + push * wz)
    bend = c < MIN_SHADING_COSINE
    return ti.select(bend, bx, sx), ti.select(bend, by, sy), ti.select(bend, bz, sz)


@ti.func
def sides_agree(sx, sy, sz, nx, ny, nz, ox, oy, oz, ix, iy, iz):
    """Mask of the lanes where the shading normal s and the geometric normal n both call the pair
    of directions (o toward the viewer, i the other) a reflection, or both a transmission."""
    shading = dot(ix, iy, iz, sx, sy, sz) * dot(ox, oy, oz, sx, sy, sz) > 0.0
    geometric = dot(ix, iy, iz, nx, ny, nz) * dot(ox, oy, oz, nx, ny, nz) > 0.0
    return mask(mask(shading) == mask(geometric))

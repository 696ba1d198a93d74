"""What a packet's rays hit, lane by lane: the point, the geometric normal, the spawn clearance and
the material, as MeshGeometry.surface has them for triangles, quads and spheres.

A lane's primitive is its own, so its record (renderer/packets/records.py: a base point and two
edges, one form for every kind) is gathered lane by lane; everything after the gather is lane
arithmetic. Points come from the hit's surface coordinates (base + b1 e1 + b2 e2), not from
o + t d, so they stay on the primitive's plane to f32 precision, as in the scalar code; a
sphere's point is put back onto it along its normal.
"""
import taichi as ti

from renderer.geometry.intersect import CLEARANCE_ROUNDOFFS, F32_UNIT_ROUNDOFF
from renderer.packets.lanes import normalized


@ti.func
def hit_surface(records: ti.template(), has_spheres: ti.template(), prim, t, b1, b2, ox, oy, oz, dx, dy, dz):
    """(point xyz, unit geometric normal xyz, clearance, material) lanes of each ray's hit."""
    bx, by, bz, scale, ux, uy, uz, radius, vx, vy, vz, material = records.gather(prim, t)
    px = bx + b1 * ux + b2 * vx
    py = by + b1 * uy + b2 * vy
    pz = bz + b1 * uz + b2 * vz
    nx, ny, nz = normalized(uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)
    if ti.static(has_spheres):
        is_sphere = radius > 0.0
        sx, sy, sz = normalized(ox + t * dx - bx, oy + t * dy - by, oz + t * dz - bz)
        nx, ny, nz = ti.select(is_sphere, sx, nx), ti.select(is_sphere, sy, ny), ti.select(is_sphere, sz, nz)
        px = ti.select(is_sphere, bx + radius * nx, px)
        py = ti.select(is_sphere, by + radius * ny, py)
        pz = ti.select(is_sphere, bz + radius * nz, pz)
    return px, py, pz, nx, ny, nz, CLEARANCE_ROUNDOFFS * F32_UNIT_ROUNDOFF * scale, material

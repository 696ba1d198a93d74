"""Every primitive in one form for the packet path's gathers: three vec4 rows a primitive, so a
lane's surface or light point is three loads whatever its kind, with no branch on the kind
(branches per lane, unrolled for 8 or 16 lanes, compiled slowly and ran scalar: a first packet
path that read each kind's own arrays took 50 s to compile at 8 lanes and rendered the Cornell
box no faster than the scalar path; docs/findings.md).

  row 0: base point xyz, the magnitude the primitive's points are computed at (spawn clearance)
  row 1: first edge xyz, the sphere's radius (0: a flat primitive)
  row 2: second edge xyz, the primitive's material row (as a float: exact below 2^24)

A triangle is v0, v1 - v0, v2 - v0; a quad its corner and edges; a sphere its centre, no edges
and its radius. 48 bytes a primitive, beside the BVH's own data.
"""
import numpy as np
import taichi as ti

from renderer.runtime.upload import upload_fields

ROWS = 3


def primitive_records(data) -> np.ndarray:
    """(P, 3, 4) float32 records of a MeshData's triangles, spheres and quads, in global id order
    (triangles, spheres, quads: the only kinds the packet path takes)."""
    tri = data.tri_vertices.astype(np.float64)
    spheres = np.asarray(data.spheres, np.float64).reshape(-1, 4)
    quads = np.asarray(data.quads, np.float64).reshape(-1, 3, 3)
    out = np.zeros((len(tri) + len(spheres) + len(quads), ROWS, 4))
    t, s = len(tri), len(spheres)
    if t:
        out[:t, 0, :3] = tri[:, 0]
        out[:t, 1, :3] = tri[:, 1] - tri[:, 0]
        out[:t, 2, :3] = tri[:, 2] - tri[:, 0]
        out[:t, 0, 3] = np.abs(tri).max(axis=(1, 2))
    if s:
        out[t:t + s, 0, :3] = spheres[:, :3]
        out[t:t + s, 1, 3] = spheres[:, 3]
        out[t:t + s, 0, 3] = np.abs(spheres[:, :3]).max(axis=1) + spheres[:, 3]
    if len(quads):
        out[t + s:, :, :3] = quads
        out[t + s:, 0, 3] = np.abs(quads).max(axis=2).sum(axis=1)
    out[:, 2, 3] = data.materials()[:len(out)]
    return out.astype(np.float32)


@ti.data_oriented
class PrimitiveRecords:
    def __init__(self, data):
        records = primitive_records(data)
        self.count = len(records)
        self.rows = ti.Vector.field(4, ti.f32, shape=(max(1, self.count), ROWS))
        if self.count:
            upload_fields([(self.rows, records)])

    def device_bytes(self) -> int:
        return self.count * ROWS * 16

    @ti.func
    def gather(self, prim, like):
        """Every lane's record, as lanes: (base xyz, scale, e1 xyz, radius, e2 xyz, material).
        `like`: float lanes for the width; lanes whose prim is < 0 read primitive 0's."""
        bx, by, bz, scale = like * 0.0, like * 0.0, like * 0.0, like * 0.0
        ux, uy, uz, radius = like * 0.0, like * 0.0, like * 0.0, like * 0.0
        vx, vy, vz, material = like * 0.0, like * 0.0, like * 0.0, like * 0.0
        for k in ti.static(range(like.n)):
            g = ti.max(prim[k], 0)
            r0, r1, r2 = self.rows[g, 0], self.rows[g, 1], self.rows[g, 2]
            bx[k], by[k], bz[k], scale[k] = r0.x, r0.y, r0.z, r0.w
            ux[k], uy[k], uz[k], radius[k] = r1.x, r1.y, r1.z, r1.w
            vx[k], vy[k], vz[k], material[k] = r2.x, r2.y, r2.z, r2.w
        return bx, by, bz, scale, ux, uy, uz, radius, vx, vy, vz, ti.cast(material, ti.i32)

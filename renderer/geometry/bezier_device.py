"""Bezier patches on the device: their fields, the leaf test in world space, and shading data.

MeshGeometry creates one of these only when the scene has Bezier surfaces, so other scenes compile
none of this. Rays reach patches in world space and are mapped into their object's frame (an
affine map keeps t, so no renormalisation); shading data goes back out with the object's matrix
(points, tangents) and its inverse transpose (normals).
"""
import numpy as np
import taichi as ti

from renderer.geometry import bezier_newton as newton
from renderer.geometry.mesh_data import MeshData

vec3 = ti.math.vec3
vec4 = ti.math.vec4
# Newton's tolerance on |S - ray| relative to the object's size. f32 evaluates S to about 1e-7 of
# the size, so 1e-6 is reached in one step beyond that noise; it stays below the spawn offset
# (256 ulps of the hit point, offset_ray_origin), so a spawned ray cannot "converge" back onto
# the surface it leaves.
RELATIVE_EPS = 1e-6


def _object_rows(data: MeshData):
    """Per object: inverse rows (object <- world, 3x4), normal rows (inverse transpose, 3x3),
    (Newton tolerance, tangent handedness)."""
    n = len(data.bezier_objects)
    inv = np.zeros((n, 3, 4))
    normal = np.zeros((n, 3, 3))
    info = np.zeros((n, 2))
    for o in range(n):
        m = data.bezier_objects[o].astype(np.float64)
        a = np.linalg.inv(m[:, :3])
        inv[o, :, :3] = a
        inv[o, :, 3] = -a @ m[:, 3]
        normal[o] = a.T
        size = np.abs(data.bezier_curves[data.bezier_curve_object == o]).max()
        info[o] = (RELATIVE_EPS * size, 1.0 if np.linalg.det(m[:, :3]) > 0 else -1.0)
    return inv, normal, info


@ti.data_oriented
class BezierPatches:
    def __init__(self, data: MeshData, uploads: list):
        """uploads: the caller's (field, array) list, copied to the device in one launch with the
        rest of the mesh (renderer.runtime.upload)."""
        def upload(array):
            array = np.asarray(array)
            f = ti.Vector.field(array.shape[-1], ti.f32, shape=array.shape[:-1])
            uploads.append((f, array))
            return f

        box = data.bezier_patch_box
        self.patch_range = upload(data.bezier_patches)
        self.patch_lo = upload(box[:, 0])
        self.patch_hi = upload(box[:, 1])
        self.patch_curve = ti.field(ti.i32, shape=len(data.bezier_patch_curve))
        uploads.append((self.patch_curve, data.bezier_patch_curve))
        self.curve_r = upload(data.bezier_curves[:, :, 0])
        self.curve_h = upload(data.bezier_curves[:, :, 1])
        self.curve_u = upload(data.bezier_curve_u)
        self.curve_object = ti.field(ti.i32, shape=len(data.bezier_curve_object))
        uploads.append((self.curve_object, data.bezier_curve_object))
        inv, normal, info = _object_rows(data)
        self.to_world = upload(data.bezier_objects)  # (objects, 3) rows
        self.to_object = upload(inv)
        self.normal_rows = upload(normal)
        self.info = upload(info)

    @ti.func
    def intersect(self, i, o, d, t_max):
        """Patch i against the world ray o + t d, t in (0, t_max): (hit, t, u, phi)."""
        c = self.patch_curve[i]
        obj = self.curve_object[c]
        a0, a1, a2 = self.to_object[obj, 0], self.to_object[obj, 1], self.to_object[obj, 2]
        oo = vec3(a0.xyz.dot(o) + a0.w, a1.xyz.dot(o) + a1.w, a2.xyz.dot(o) + a2.w)
        od = vec3(a0.xyz.dot(d), a1.xyz.dot(d), a2.xyz.dot(d))
        hit, t, u, phi, _ = newton.patch_hit(self.curve_r[c], self.curve_h[c], self.patch_range[i],
                                             self.patch_lo[i], self.patch_hi[i], oo, od, t_max, self.info[obj].x)
        return hit, t, u, phi

    @ti.func
    def surface(self, i, u, phi):
        """World point, outward normal, texture coordinates and tangent (xyz along +u, w the
        handedness for bitangent = w * n x t, which runs along +phi) at (u, phi) of patch i."""
        c = self.patch_curve[i]
        obj = self.curve_object[c]
        cr = self.curve_r[c]
        ch = self.curve_h[c]
        r, h, dr, dh = newton.profile(cr, ch, u)
        scale = ti.abs(cr).max() + ti.abs(ch).max()
        if dr * dr + dh * dh <= 1e-12 * scale * scale:
            # A repeated control point stops the curve at an end (or a cusp): its tangent is the
            # limit direction, taken by a small central difference.
            ua = ti.max(u - 1e-3, 0.0)
            ub = ti.min(u + 1e-3, 1.0)
            ra, ha, _, _ = newton.profile(cr, ch, ua)
            rb, hb, _, _ = newton.profile(cr, ch, ub)
            dr = rb - ra
            dh = hb - ha
        cs = ti.cos(phi)
        sn = ti.sin(phi)
        p_obj = vec3(r * cs, h, r * sn)
        # S_u x S_phi divided by r: defined on the axis too (r = 0), where S_phi vanishes.
        n_obj = vec3(dh * cs, -dr, dh * sn)
        t_obj = vec3(dr * cs, dh, dr * sn)
        if n_obj.dot(n_obj) <= 1e-24 * scale * scale:
            n_obj = vec3(0.0, 1.0, 0.0)  # a profile collapsed to a point: the axis direction
        m0, m1, m2 = self.to_world[obj, 0], self.to_world[obj, 1], self.to_world[obj, 2]
        p = vec3(m0.xyz.dot(p_obj) + m0.w, m1.xyz.dot(p_obj) + m1.w, m2.xyz.dot(p_obj) + m2.w)
        tw = vec3(m0.xyz.dot(t_obj), m1.xyz.dot(t_obj), m2.xyz.dot(t_obj))
        k0, k1, k2 = self.normal_rows[obj, 0], self.normal_rows[obj, 1], self.normal_rows[obj, 2]
        n = ti.math.normalize(vec3(k0.dot(n_obj), k1.dot(n_obj), k2.dot(n_obj)))
        tw = tw - n.dot(tw) * n
        tangent = vec4(0.0)
        if tw.dot(tw) > 0.0:
            tangent = vec4(ti.math.normalize(tw), self.info[obj].y)
        cu = self.curve_u[c]
        uv = ti.math.vec2(cu.x + cu.y * u, ti.math.clamp(phi / newton.TWO_PI, 0.0, 1.0))
        return p, n, uv, tangent

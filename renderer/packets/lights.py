"""Light samples for a packet of path vertices: the scene's emissive triangles, quads and spheres,
chosen by power (Vose's alias table, one gather per lane; a sphere's point by the cone it subtends,
renderer/packets/sphere_lights.py), and the environment: a constant one lane by lane,
a map or a sky through renderer/lights/lights.py's environment_direction, one lane after another
(a map importance-sampled as the scalar path samples it).

The packet path keeps its own light selection, so its densities are its own: the emitters by
their power (light_select.alias_table over renderer/lights/lights.py's emitter_table), the
environment with the share renderer/lights/lights.py gives it (half where emitters exist too),
directions on it as environment_direction draws them. MIS at a BSDF-sampled hit asks the same densities back (pdf_hit,
pdf_environment), so the estimator is unbiased whatever the scalar path's light tree would have
chosen: images agree with the scalar path's in expectation (tests/packets test that).
"""
import math

import numpy as np
import taichi as ti

from renderer.lights.light_select import alias_table
from renderer.lights.env_sampling import EnvironmentSampler
from renderer.lights.lights import ENVIRONMENT_SHARE, emitter_table, environment_direction, environment_emits
from renderer.packets import sphere_lights
from renderer.packets.lanes import normalized, sincos_2pi
from renderer.runtime.upload import upload_fields

INV_4PI = 1.0 / (4.0 * math.pi)


@ti.data_oriented
class PacketLights:
    """Emitter selection on the device: alias columns (q, alias), each emitter's primitive, and
    per primitive the density of choosing a point on it by area (its pmf / area; 0 for
    primitives that do not emit). `has_env`, `has_emitters`, `has_spheres` (an emitter is a
    sphere): compile-time, from the scene."""

    def __init__(self, geometry, records, materials, environment, environment_spec, env_image=None):
        """geometry: a MeshGeometry; records: its PrimitiveRecords; materials: its MaterialTable;
        environment: the device Environment; env_image: the map of a "map" environment."""
        self.geometry = geometry
        self.records = records
        self.triangle_end = geometry.data.counts["triangle"]
        self.materials = materials
        self.environment = environment
        self.has_env = environment_emits(environment_spec)
        self.env_constant = environment_spec.kind == "constant"
        self.env_is_map = self.has_env and environment_spec.kind == "map"  # (names environment_direction reads)
        self.env_sampler = EnvironmentSampler(env_image, environment) if self.env_is_map else None
        self.primitive_count = int(geometry.primitive_count())
        # Built once: an edit of emission or of the environment makes the Renderer drop its packet
        # programs and these lights with them (Renderer._drop_packet_programs).
        table = emitter_table(geometry, materials.arrays)
        prims = table["prim"]
        self.has_emitters = len(prims) > 0
        sphere_end = self.triangle_end + geometry.data.counts["sphere"]
        self.has_spheres = bool(((prims >= self.triangle_end) & (prims < sphere_end)).any())
        n = max(1, len(prims))
        q, alias, prim = np.ones(n, np.float32), np.zeros(n, np.int32), np.zeros(n, np.int32)
        density = np.zeros(max(1, self.primitive_count), np.float32)
        if self.has_emitters:
            q[:len(prims)], alias[:len(prims)], pmf = alias_table(table["power"])
            prim[:len(prims)] = prims
            density[prims] = pmf / table["area"]
        self.q = ti.field(ti.f32, shape=n)
        self.alias = ti.field(ti.i32, shape=n)
        self.prim = ti.field(ti.i32, shape=n)
        self.density = ti.field(ti.f32, shape=len(density))
        upload_fields([(self.q, q), (self.alias, alias), (self.prim, prim), (self.density, density)])
        self.count = ti.field(ti.i32, shape=())
        self.count[None] = len(prims)
        self.env_share = ti.field(ti.f32, shape=())
        self.env_share[None] = (ENVIRONMENT_SHARE if self.has_emitters else 1.0) if self.has_env else 0.0

    @ti.func
    def sample(self, px, py, pz, u_select, u1, u2):
        """Light samples seen from the points p (lanes): (direction xyz, distance (INF towards the
        environment), solid-angle density, the point and its normal xyz (for the shadow ray's far
        end), radiance rgb, prim (-1: the environment)). Density 0: nothing to add."""
        share = self.env_share[None]
        use_env = u_select < share
        u = ti.select(use_env, u_select / ti.max(share, 1e-30), (u_select - share) / ti.max(1.0 - share, 1e-30))
        count = self.count[None]
        column_f = u * count
        column = ti.min(ti.cast(column_f, ti.i32), count - 1)
        column = ti.max(column, 0)
        frac = column_f - ti.cast(column, ti.f32)
        prim = column
        for k in ti.static(range(u.n)):
            j = column[k]
            prim[k] = self.prim[ti.select(frac[k] < self.q[j], j, self.alias[j])]
        bx, by, bz, scale, ux, uy, uz, radius, vx, vy, vz, material = self.records.gather(prim, u)
        # a triangle's point (v0 + b1 e1 + b2 e2, sqrt-warped) or a quad's (u1, u2) directly
        is_triangle = prim < self.triangle_end
        su = ti.sqrt(u1)
        b1 = ti.select(is_triangle, 1.0 - su, u1)
        b2 = ti.select(is_triangle, u2 * su, u2)
        qx = bx + b1 * ux + b2 * vx
        qy = by + b1 * uy + b2 * vy
        qz = bz + b1 * uz + b2 * vz
        cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        length = ti.sqrt(cx * cx + cy * cy + cz * cz)
        area = ti.select(is_triangle, 0.5 * length, length)
        inv_len = 1.0 / ti.max(length, 1e-30)
        nx, ny, nz = cx * inv_len, cy * inv_len, cz * inv_len
        by_cone = prim * 0  # sphere lanes whose point was drawn in the cone they subtend
        cone = u * 0.0
        if ti.static(self.has_spheres):
            is_sphere = radius > 0.0
            sx, sy, sz, snx, sny, snz, inside, cone = sphere_lights.sample(bx, by, bz, radius, px, py, pz, u1, u2)
            qx, qy, qz = ti.select(is_sphere, sx, qx), ti.select(is_sphere, sy, qy), ti.select(is_sphere, sz, qz)
            nx, ny, nz = ti.select(is_sphere, snx, nx), ti.select(is_sphere, sny, ny), ti.select(is_sphere, snz, nz)
            area = ti.select(is_sphere, 4.0 * math.pi * radius * radius, area)
            by_cone = ti.select(is_sphere & (inside == 0), 1, 0)
        wx, wy, wz = qx - px, qy - py, qz - pz
        dist2 = wx * wx + wy * wy + wz * wz
        dist = ti.sqrt(dist2)
        wx, wy, wz = normalized(wx, wy, wz)
        cos_l = -(nx * wx + ny * wy + nz * wz)  # > 0: the point's front faces p
        pmf_area = u * 0.0
        er, eg, eb = u * 0.0, u * 0.0, u * 0.0
        two_sided = prim * 0
        for k in ti.static(range(u.n)):
            pmf_area[k] = self.density[prim[k]]
            emission = self.materials.table[material[k]].emission
            er[k], eg[k], eb[k] = emission.x, emission.y, emission.z
            two_sided[k] = self.materials.table[material[k]].two_sided_emission
        pdf = (1.0 - share) * pmf_area * dist2 / ti.max(ti.abs(cos_l), 1e-30)
        if ti.static(self.has_spheres):  # by the cone: the sphere's chance (pmf_area x area) over its solid angle
            pdf = ti.select(by_cone == 1, (1.0 - share) * pmf_area * area / ti.max(cone, 1e-30), pdf)
        lit = (cos_l > 0.0) | (two_sided != 0)
        ok = (area > 0.0) & (ti.abs(cos_l) > 0.0) & (dist2 > 0.0) & (count > 0)
        pdf = ti.select(ok, pdf, 0.0)
        er, eg, eb = ti.select(lit, er, 0.0), ti.select(lit, eg, 0.0), ti.select(lit, eb, 0.0)
        if ti.static(self.has_env):
            # directions as renderer/lights/lights.py's environment_direction draws them: uniform
            # (lane arithmetic where the radiance is one colour), or one lane after another
            z = 1.0 - 2.0 * u1
            r = ti.sqrt(ti.max(0.0, 1.0 - z * z))
            s, c = sincos_2pi(u2)
            ex, ey, ez = r * c, z, r * s
            env_pdf = u * 0.0 + INV_4PI
            env = self.environment.radiance(ti.math.vec3(0.0, 1.0, 0.0))
            vr, vg, vb = u * 0.0 + env.x, u * 0.0 + env.y, u * 0.0 + env.z
            if ti.static(not self.env_constant):
                for k in range(u.n):
                    if use_env[k]:
                        d, p, radiance = environment_direction(self, ti.math.vec2(u1[k], u2[k]))
                        ex[k], ey[k], ez[k], env_pdf[k] = d.x, d.y, d.z, p
                        vr[k], vg[k], vb[k] = radiance.x, radiance.y, radiance.z
            wx, wy, wz = ti.select(use_env, ex, wx), ti.select(use_env, ey, wy), ti.select(use_env, ez, wz)
            dist = ti.select(use_env, 1e30, dist)
            pdf = ti.select(use_env, share * env_pdf, pdf)
            er, eg, eb = ti.select(use_env, vr, er), ti.select(use_env, vg, eg), ti.select(use_env, vb, eb)
            prim = ti.select(use_env, -1, prim)
        return wx, wy, wz, dist, pdf, qx, qy, qz, nx, ny, nz, er, eg, eb, prim

    @ti.func
    def pdf_hit(self, prim, dist2, cos_l, ox, oy, oz):
        """The solid-angle density with which `sample` would have chosen, from the points o, the
        point a BSDF-sampled ray hit on `prim` at squared distance dist2, where the ray meets its
        surface at cosine cos_l (lanes)."""
        density = cos_l * 0.0
        for k in ti.static(range(cos_l.n)):
            density[k] = self.density[ti.max(prim[k], 0)]
        pdf = (1.0 - self.env_share[None]) * density * dist2 / ti.max(ti.abs(cos_l), 1e-30)
        if ti.static(self.has_spheres):
            bx, by, bz, scale, ux, uy, uz, radius, vx, vy, vz, material = self.records.gather(prim, cos_l)
            inside, per_cone = sphere_lights.pdf_scale(bx, by, bz, radius, ox, oy, oz)
            by_cone = (radius > 0.0) & (inside == 0)
            pdf = ti.select(by_cone, (1.0 - self.env_share[None]) * density * 4.0 * math.pi * radius * radius
                            * per_cone, pdf)
        return pdf

    @ti.func
    def environment_seen(self, dx, dy, dz, missed):
        """The environment's radiance (rgb lanes) along the directions d of the lanes in `missed`
        (0 elsewhere), and the solid-angle density with which `sample` would have chosen them."""
        env = self.environment.radiance(ti.math.vec3(0.0, 1.0, 0.0))
        vr, vg, vb = dx * 0.0 + env.x, dx * 0.0 + env.y, dx * 0.0 + env.z
        pdf = dx * 0.0 + self.env_share[None] * INV_4PI
        if ti.static(not self.env_constant):
            for k in range(dx.n):
                if missed[k] == 1:
                    d = ti.math.vec3(dx[k], dy[k], dz[k])
                    radiance = self.environment.radiance(d)
                    vr[k], vg[k], vb[k] = radiance.x, radiance.y, radiance.z
                    if ti.static(self.env_is_map):
                        pdf[k] = self.env_share[None] * self.env_sampler.pdf(d)
        return vr, vg, vb, pdf

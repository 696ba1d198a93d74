"""The path tracer (`path`, `nee`, `mis`) for a packet of camera rays, lane by lane: the estimator
of renderer/integrators/tracer.py for the scenes renderer/packets/support.py admits (Lambert
surfaces, emissive triangles and quads, a constant environment, no media).

Every lane is a path; the packet takes its vertices together (one closest-hit trace, then one
shadow trace, per vertex) and a path that ends is masked off until all have. The depth limit, the
roulette (from RR_DEPTH bounces, survival min(max throughput, 0.95)), the sampler's dimensions
per decision, the MIS weights (power heuristic) and the emission rules (the front face, or both
faces where the material says so) are the scalar tracer's; light selection is PacketLights'.
"""
import taichi as ti

from renderer.geometry.interface import INF
from renderer.integrators.tracer import MAX_VERTICES, RR_DEPTH
from renderer.packets import traversal
from renderer.packets.lanes import any_lane, cosine_hemisphere, mask, offset_origin, seeded
from renderer.packets.surfaces import hit_surface
from renderer.sampling import dims
from renderer.sampling.rng import uniform

INV_PI = 0.31830988618379067


@ti.func
def power_heuristic(a, b):
    """light_sampling.power_heuristic lane by lane: a^2 / (a^2 + b^2) through the ratio of the
    smaller density to the larger, so an infinite density gives 1 or 0, never inf / inf."""
    a_larger = a >= b
    r = ti.select(a_larger, b / ti.max(a, 1e-30), a / ti.max(b, 1e-30))
    r2 = r * r
    w = ti.select(a_larger, 1.0 / (1.0 + r2), r2 / (1.0 + r2))
    return ti.select(a_larger & (a > 0.0), w, ti.select(b > a, w, 0.0))


@ti.func
def uniform2(key, dim):
    """IndependentSampler.get2d, lane by lane: the same numbers for the same key and dimension."""
    return uniform(key, dim), uniform(key, dim + 0x4000)


@ti.func
def leave(px, py, pz, nx, ny, nz, eps, toward):
    """MeshGeometry._leave: the point moved off its surface by its clearance, then by a few ulps,
    on the side of the normal n that `toward` (the dot product of the direction and n) points to."""
    side = ti.select(toward > 0.0, 1.0, -1.0)
    sx, sy, sz = side * nx, side * ny, side * nz
    return offset_origin(px + eps * sx, py + eps * sy, pz + eps * sz, sx, sy, sz)


@ti.func
def trace_paths(ctx: ti.template(), key, ox, oy, oz, dx, dy, dz, live_in, max_depth):
    """The radiance (rgb lanes) of the camera rays (o, d) of the live lanes, the work done:
    (node visits, primitive tests, rays) lanes, the packet's visits and tests counted in every
    lane that took part, the packet's occupancy: (closest-hit traces, the live lanes they
    carried, shadow traces, their live lanes), and the sum of the lanes lanes.seeded read, which
    the caller must store somewhere (a product with 0 would be folded away, and the stores with it)."""
    light_sampling = ti.static(ctx.integrator.light_sampling)
    use_mis = ti.static(ctx.integrator.mis)
    geometry = ctx.geometry
    zero = ox * 0.0
    lr, lg, lb = zero, zero, zero
    tr, tg, tb = zero + 1.0, zero + 1.0, zero + 1.0
    prev_x, prev_y, prev_z = ox, oy, oz
    prev_pdf = zero
    prev_delta = live_in  # the camera: what it sees directly is not light-sampled
    live = live_in
    visits, tests, rays = zero, zero, zero
    env = ctx.environment.radiance(ti.math.vec3(0.0, 1.0, 0.0))
    bounces = 0
    seeds = 0.0
    occupancy = ti.math.ivec4(0)
    for _ in range(MAX_VERTICES):
        if not any_lane(live):
            break
        dim = dims.BOUNCE_BASE + dims.PER_BOUNCE * bounces
        prim, t, b1, b2, v, n_tests = traversal.trace(geometry, ox, oy, oz, dx, dy, dz,
                                                      ti.select(live == 1, INF, -1.0), False)
        took = ti.cast(live, ti.f32)
        occupancy += ti.math.ivec4(1, live.sum(), 0, 0)
        visits += took * v
        tests += took * n_tests
        rays += took
        missed = live & mask(prim < 0)
        if ti.static(ctx.lights.has_env):
            weight = zero + 1.0
            if ti.static(light_sampling):
                other = ti.select(prev_delta == 1, 1.0, power_heuristic(prev_pdf, zero + ctx.lights.pdf_environment()))
                weight = other if ti.static(use_mis) else ti.select(prev_delta == 1, 1.0, 0.0)
            lr += ti.select(missed == 1, tr * weight * env.x, 0.0)
            lg += ti.select(missed == 1, tg * weight * env.y, 0.0)
            lb += ti.select(missed == 1, tb * weight * env.z, 0.0)
        live &= mask(prim >= 0)
        if not any_lane(live):
            break
        px, py, pz, nx, ny, nz, eps, material = hit_surface(ctx.records, ti.static("sphere" in geometry.kinds), prim, t,
                                                            b1, b2, ox, oy, oz, dx, dy, dz)
        cos_o = -(dx * nx + dy * ny + dz * nz)  # wo . n: > 0 on the front face
        ar, ag, ab = zero, zero, zero
        er, eg, eb = zero, zero, zero
        two_sided = live * 0
        for k in ti.static(range(ox.n)):
            row = ctx.materials.table[material[k]]
            ar[k], ag[k], ab[k] = row.base_color.x, row.base_color.y, row.base_color.z
            er[k], eg[k], eb[k] = row.emission.x, row.emission.y, row.emission.z
            two_sided[k] = row.two_sided_emission
        # emission found by the ray
        emits = live & mask((cos_o > 0.0) | (two_sided != 0)) & mask(ti.max(er, ti.max(eg, eb)) > 0.0)
        if any_lane(emits):
            weight = zero + 1.0
            if ti.static(light_sampling):
                wx, wy, wz = px - prev_x, py - prev_y, pz - prev_z
                dist2 = wx * wx + wy * wy + wz * wz
                cos_l = (wx * nx + wy * ny + wz * nz) / ti.sqrt(ti.max(dist2, 1e-30))
                light_pdf = ctx.lights.pdf_hit(prim, dist2, cos_l)
                sampled = (prev_delta == 0) & (light_pdf > 0.0)
                if ti.static(use_mis):
                    weight = ti.select(sampled, power_heuristic(prev_pdf, light_pdf), 1.0)
                else:
                    weight = ti.select(sampled, 0.0, 1.0)
            lr += ti.select(emits == 1, tr * weight * er, 0.0)
            lg += ti.select(emits == 1, tg * weight * eg, 0.0)
            lb += ti.select(emits == 1, tb * weight * eb, 0.0)
        if max_depth >= 0 and bounces + 1 >= max_depth:
            break
        # the Lambert lobe on wo's side of the surface
        side = ti.select(cos_o >= 0.0, 1.0, -1.0)
        fx, fy, fz = side * nx, side * ny, side * nz
        if ti.static(light_sampling):
            u1, u2 = uniform2(key, dim + dims.LIGHT_POINT)
            wx, wy, wz, dist, pdf, qx, qy, qz, qnx, qny, qnz, rr, rg, rb, light = ctx.lights.sample(
                px, py, pz, uniform(key, dim + dims.LIGHT_SELECT), u1, u2)
            cos_i = wx * fx + wy * fy + wz * fz
            scale = zero + 1.0 / ti.max(pdf, 1e-30)
            if ti.static(use_mis):
                scale *= power_heuristic(pdf, cos_i * INV_PI)
            found = live & mask((pdf > 0.0) & (ti.max(rr, ti.max(rg, rb)) > 0.0) & (cos_i > 0.0))
            if any_lane(found):
                sx, sy, sz = leave(px, py, pz, nx, ny, nz, eps, wx * nx + wy * ny + wz * nz)
                # the far end off the light's own surface (next_segment), or the environment
                far_side = ti.select((sx - qx) * qnx + (sy - qy) * qny + (sz - qz) * qnz > 0.0, 1.0, -1.0)
                ex, ey, ez = offset_origin(qx, qy, qz, far_side * qnx, far_side * qny, far_side * qnz)
                gx, gy, gz = ex - sx, ey - sy, ez - sz
                length = ti.sqrt(gx * gx + gy * gy + gz * gz)
                inv_len = 1.0 / ti.max(length, 1e-30)
                to_env = light < 0
                gx = ti.select(to_env, wx, gx * inv_len)
                gy = ti.select(to_env, wy, gy * inv_len)
                gz = ti.select(to_env, wz, gz * inv_len)
                t_max = ti.select(to_env, INF, length * (1.0 - 1e-4))
                t_max = ti.select((found == 1) & (length > 0.0), t_max, -1.0)
                # (distinct names: `_` taken twice in one unpacking miscompiles in Taichi 1.7.4)
                blocker, t_blocker, b1_blocker, b2_blocker, sv, st = traversal.trace(geometry, sx, sy, sz, gx, gy, gz,
                                                                                     t_max, True)
                took = ti.cast(mask(t_max >= 0.0), ti.f32)
                occupancy += ti.math.ivec4(0, 0, 1, mask(t_max >= 0.0).sum())
                visits += took * sv
                tests += took * st
                rays += took
                add = (t_max >= 0.0) & (blocker < 0)
                f = cos_i * INV_PI * scale
                lr += ti.select(add, tr * ar * f * rr, 0.0)
                lg += ti.select(add, tg * ag * f * rg, 0.0)
                lb += ti.select(add, tb * ab * f * rb, 0.0)
        # the next direction: cosine-weighted about the side's normal
        v1, v2 = uniform2(key, dim + dims.BSDF_DIRECTION)
        wx, wy, wz, cos_t = cosine_hemisphere(v1, v2, fx, fy, fz)
        live &= mask(cos_t > 0.0)
        tr, tg, tb = tr * ar, tg * ag, tb * ab
        prev_x, prev_y, prev_z = px, py, pz
        prev_pdf = cos_t * INV_PI
        prev_delta = live * 0
        ox, oy, oz = leave(px, py, pz, nx, ny, nz, eps, wx * nx + wy * ny + wz * nz)
        dx, dy, dz = wx, wy, wz
        if bounces >= RR_DEPTH:
            q = ti.min(ti.max(tr, ti.max(tg, tb)), 0.95)
            survives = uniform(key, dim + dims.ROULETTE) < q
            live &= mask(survives)
            inv_q = 1.0 / ti.max(q, 1e-30)
            tr, tg, tb = tr * inv_q, tg * inv_q, tb * inv_q
        # The path's state stored lane by lane (lanes.seeded): what LLVM vectorises the bounce from.
        j = bounces & (ox.n - 1)
        ox, s0 = seeded(ox, j)
        oy, s1 = seeded(oy, j)
        oz, s2 = seeded(oz, j)
        dx, s3 = seeded(dx, j)
        dy, s4 = seeded(dy, j)
        dz, s5 = seeded(dz, j)
        tr, s6 = seeded(tr, j)
        tg, s7 = seeded(tg, j)
        tb, s8 = seeded(tb, j)
        lr, s9 = seeded(lr, j)
        lg, s10 = seeded(lg, j)
        lb, s11 = seeded(lb, j)
        prev_pdf, s12 = seeded(prev_pdf, j)
        seeds += s0 + s1 + s2 + s3 + s4 + s5 + s6 + s7 + s8 + s9 + s10 + s11 + s12
        bounces += 1
    return lr, lg, lb, visits, tests, rays, occupancy, seeds

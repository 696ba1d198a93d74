"""The path tracer (`path`, `nee`, `mis`) for a packet of camera rays, lane by lane: the estimator
of renderer/integrators/tracer.py for the scenes renderer/packets/support.py admits (every material
kind but the null boundary, textures, maps and shading normals, emissive triangles, quads and
spheres of one colour, any environment, no media).

Lambert surfaces and rough GGX conductors (lambert.py, conductor.py) are shaded in lane
arithmetic, about the shading normal (vertex normals interpolated, shading_normals.py). Lanes on
any other kind of material (delta mirrors included), and every
lane where the look of a surface point needs the geometry's own record (textures, maps, vertex
colours: the program's surface_records), are `general`: compiled only where a scene has them,
they take the scalar BSDF (renderer/materials/bsdf.py) one lane after another in a run-time loop:
its value and density toward the light sample and its own sample, with the same random numbers
per decision as the scalar tracer. Rays carry cones for texture filtering as the scalar path's.
Traversal, light selection, emission, MIS and roulette stay packet-wide for every lane.

Every lane is a path; the packet takes its vertices together (one closest-hit trace, then one
shadow trace, per vertex) and a path that ends is masked off until all have. The depth limit, the
roulette (from RR_DEPTH bounces, survival min(max throughput, 0.95)), the sampler's dimensions
per decision, the MIS weights (power heuristic) and the emission rules (the front face, or both
faces where the material says so) are the scalar tracer's; light selection is PacketLights'.
"""
import taichi as ti

from renderer.geometry.interface import INF, Hit, Ray, Surface
from renderer.integrators.tracer import MAX_VERTICES, RR_DEPTH
from renderer.materials.kinds import KIND_IDS
from renderer.materials.microfacet import head_on_reflectance
from renderer.materials.table import alpha_of
from renderer.packets import conductor as conductor_lanes
from renderer.packets import lambert, traversal
from renderer.packets.lanes import any_lane, mask, offset_origin, seeded
from renderer.packets.shading_normals import consistent_normals, interpolated_normals
from renderer.packets.surfaces import hit_surface
from renderer.sampling import dims
from renderer.sampling.rng import uniform
from renderer.sampling.warps import INV_PI

DIFFUSE = KIND_IDS["diffuse"]
CONDUCTOR = KIND_IDS["conductor"]


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
def _general_lanes(ctx: ti.template(), toward_light: ti.template(), last, key, dim, general, ox, oy, oz, t, b1,
                   b2, prim, cone, spread, px, py, pz, nx, ny, nz, snx, sny, snz, dx, dy, dz, material, wx, wy, wz,
                   v1, v2, bsdf_pdf, usable, bx, by, bz, weight_r, weight_g, weight_b, next_pdf, next_valid,
                   next_delta):
    """The lanes of `general` (materials other than Lambert's) through the scalar BSDF, one after
    another (a run-time loop: the BSDF's code is compiled once, not once a lane): with
    toward_light, f cos and the density toward the light direction w (0 where the material has no
    smooth part, as the scalar tracer samples no light there); then the BSDF's own sample, from
    the numbers (BSDF_LOBE, v1, v2) the scalar tracer draws. The ray (o, its cone's width and
    spread) and its hit (t, b1, b2, prim) make the geometry's own surface record where the program
    takes surface records (otherwise the record is the point's, its geometric normal's and its
    shading normal's sn, all an untextured material reads of it). `last`: the path's last vertex,
    which only shades (for its AOVs). Returns the lanes given, with the general lanes' values in place: (f cos rgb, bsdf_pdf,
    usable, the next direction xyz, its weight rgb, pdf, valid, delta), then the general lanes'
    AOV albedo rgb and shading normal xyz and whether the material has a smooth part."""
    gr, gg, gb = wx * 0.0, wx * 0.0, wx * 0.0
    albedo_r, albedo_g, albedo_b = wx * 0.0, wx * 0.0, wx * 0.0
    shading_x, shading_y, shading_z = wx * 0.0, wx * 0.0, wx * 0.0
    smooth = general * 0
    lobe = uniform(key, dim + dims.BSDF_LOBE)
    for k in range(general.n):
        if general[k] == 1:
            n = ti.math.vec3(nx[k], ny[k], nz[k])
            wo = -ti.math.vec3(dx[k], dy[k], dz[k])
            surface = Surface()
            if ti.static(ctx.surface_records):
                surface = ctx.geometry.surface(
                    Ray(o=ti.math.vec3(ox[k], oy[k], oz[k]), d=-wo, cone_width=cone[k], cone_spread=spread[k]),
                    Hit(hit=1, t=t[k], prim=prim[k], bary=ti.math.vec2(b1[k], b2[k]), instance=-1))
                n = surface.n_geo
            else:  # what shade reads of a record without textures or maps
                surface = Surface(p=ti.math.vec3(px[k], py[k], pz[k]), n_geo=n,
                                  n_shading=ti.math.vec3(snx[k], sny[k], snz[k]), material=material[k],
                                  front_face=ti.select(wo.dot(n) > 0.0, 1, 0))
            mat, ns = ctx.bsdf.shade(surface, wo)
            has_smooth = ctx.bsdf.has_smooth_part(mat)
            colour = ctx.bsdf.albedo(mat)
            albedo_r[k], albedo_g[k], albedo_b[k] = colour.x, colour.y, colour.z
            shading_x[k], shading_y[k], shading_z[k] = ns.x, ns.y, ns.z
            smooth[k] = ti.select(has_smooth, 1, 0)
            if not last:
                if ti.static(toward_light):
                    value = ti.math.vec3(0.0)
                    density = 0.0
                    if has_smooth:
                        value, density = ctx.bsdf.eval_at(mat, ns, n, wo, ti.math.vec3(wx[k], wy[k], wz[k]))
                    gr[k], gg[k], gb[k] = value.x, value.y, value.z
                    bsdf_pdf[k] = density
                    usable[k] = ti.select(value.max() > 0.0, 1, 0)
                bs = ctx.bsdf.sample_at(mat, ns, n, wo, lobe[k], ti.math.vec2(v1[k], v2[k]))
                bx[k], by[k], bz[k] = bs.wi.x, bs.wi.y, bs.wi.z
                weight_r[k], weight_g[k], weight_b[k] = bs.weight.x, bs.weight.y, bs.weight.z
                next_pdf[k] = bs.pdf
                next_valid[k] = bs.valid
                next_delta[k] = bs.delta
    return (gr, gg, gb, bsdf_pdf, usable, bx, by, bz, weight_r, weight_g, weight_b, next_pdf, next_valid,
            next_delta, albedo_r, albedo_g, albedo_b, shading_x, shading_y, shading_z, smooth)


@ti.func
def trace_paths(ctx: ti.template(), key, ox, oy, oz, dx, dy, dz, spread, live_in, max_depth):
    """The radiance (rgb lanes) of the camera rays (o, d) of the live lanes (their cones widening
    by `spread` a unit of length, from nothing at the camera), the work done:
    (node visits, primitive tests, rays) lanes, the packet's visits and tests counted in every
    lane that took part, the packet's occupancy: (closest-hit traces, the live lanes they
    carried, shadow traces, their live lanes), and the sum of the lanes lanes.seeded read, which
    the caller must store somewhere (a product with 0 would be folded away, and the stores with it)."""
    light_sampling = ti.static(ctx.integrator.light_sampling)
    use_mis = ti.static(ctx.integrator.mis)
    has_general = ti.static(ctx.has_general)
    geometry = ctx.geometry
    zero = ox * 0.0
    cone = zero  # each ray's cone's width where it starts
    prim_none = ti.select(live_in < 0, -1, -1)
    lr, lg, lb = zero, zero, zero
    tr, tg, tb = zero + 1.0, zero + 1.0, zero + 1.0
    prev_x, prev_y, prev_z = ox, oy, oz
    prev_pdf = zero
    prev_delta = live_in  # the camera: what it sees directly is not light-sampled
    live = live_in
    visits, tests, rays = zero, zero, zero
    bounces = 0
    seeds = 0.0
    occupancy = ti.math.ivec4(0)
    # The denoiser's AOVs (RenderProgram's, where kept): the first vertex with a smooth part's albedo,
    # scaled by the delta bounces' weights before it, and its shading normal
    aovs = ti.static(ctx.writes_aovs)
    aov_r, aov_g, aov_b, aov_nx, aov_ny, aov_nz = zero, zero, zero, zero, zero, zero
    aov_wr, aov_wg, aov_wb = zero + 1.0, zero + 1.0, zero + 1.0
    aov_open = live_in
    for _ in range(MAX_VERTICES):
        if not any_lane(live):
            break
        dim = dims.BOUNCE_BASE + dims.PER_BOUNCE * bounces
        # work (node visits, primitive tests) as lanes: the packet's steps in every lane, or each ray's own
        prim, t, b1, b2, v, n_tests = prim_none, zero, zero, zero, zero, zero
        if ti.static(ctx.scalar_bounces):
            if bounces == 0:
                prim, t, b1, b2, pv, pt = traversal.trace(geometry, ox, oy, oz, dx, dy, dz,
                                                          ti.select(live == 1, INF, -1.0), False)
                v, n_tests = zero + pv, zero + pt
            else:
                prim, t, b1, b2, v, n_tests = traversal.trace_lanes(geometry, ox, oy, oz, dx, dy, dz,
                                                                    ti.select(live == 1, INF, -1.0), False)
        else:
            prim, t, b1, b2, pv, pt = traversal.trace(geometry, ox, oy, oz, dx, dy, dz,
                                                      ti.select(live == 1, INF, -1.0), False)
            v, n_tests = zero + pv, zero + pt
        took = ti.cast(live, ti.f32)
        occupancy += ti.math.ivec4(1, live.sum(), 0, 0)
        visits += took * v
        tests += took * n_tests
        rays += took
        missed = live & mask(prim < 0)
        if ti.static(ctx.lights.has_env):
            if any_lane(missed):
                vr, vg, vb, env_pdf = ctx.lights.environment_seen(dx, dy, dz, missed)
                weight = zero + 1.0
                if ti.static(light_sampling):
                    other = ti.select(prev_delta == 1, 1.0, power_heuristic(prev_pdf, env_pdf))
                    weight = other if ti.static(use_mis) else ti.select(prev_delta == 1, 1.0, 0.0)
                lr += ti.select(missed == 1, tr * weight * vr, 0.0)
                lg += ti.select(missed == 1, tg * weight * vg, 0.0)
                lb += ti.select(missed == 1, tb * weight * vb, 0.0)
                if ti.static(aovs):  # the background, as far as an albedo goes
                    seen = (missed == 1) & (aov_open == 1)
                    aov_r = ti.select(seen, aov_wr * ti.math.clamp(vr, 0.0, 1.0), aov_r)
                    aov_g = ti.select(seen, aov_wg * ti.math.clamp(vg, 0.0, 1.0), aov_g)
                    aov_b = ti.select(seen, aov_wb * ti.math.clamp(vb, 0.0, 1.0), aov_b)
        if ti.static(aovs):
            seen = (missed == 1) & (aov_open == 1)
            if ti.static(not ctx.lights.has_env):  # a black background
                aov_r, aov_g, aov_b = (ti.select(seen, 0.0, aov_r), ti.select(seen, 0.0, aov_g),
                                       ti.select(seen, 0.0, aov_b))
            aov_nx, aov_ny, aov_nz = (ti.select(seen, 0.0, aov_nx), ti.select(seen, 0.0, aov_ny),
                                      ti.select(seen, 0.0, aov_nz))
        live &= mask(prim >= 0)
        if not any_lane(live):
            break
        px, py, pz, nx, ny, nz, eps, material = hit_surface(ctx.records, ti.static("sphere" in geometry.kinds), prim, t,
                                                            b1, b2, ox, oy, oz, dx, dy, dz)
        cos_o = -(dx * nx + dy * ny + dz * nz)  # wo . n: > 0 on the front face
        # The shading normal, as the scalar path's surface record has it (consistent with the viewer;
        # where the world has vertex normals, a triangle's interpolated)
        snx, sny, snz = nx, ny, nz
        if ti.static(not ctx.surface_records):
            if ti.static(ctx.shading_normals):
                snx, sny, snz = interpolated_normals(geometry, prim, b1, b2, nx, ny, nz)
            snx, sny, snz = consistent_normals(snx, sny, snz, nx, ny, nz, -dx, -dy, -dz)
        ar, ag, ab = zero, zero, zero
        er, eg, eb = zero, zero, zero
        two_sided = live * 0
        kind = live * 0
        alpha = zero  # a rough conductor lane's GGX width (renderer/packets/conductor.py)
        albedo_r, albedo_g, albedo_b = zero, zero, zero  # the AOV albedo, Bsdf.albedo's
        for k in ti.static(range(ox.n)):
            row = ctx.materials.table[material[k]]
            ar[k], ag[k], ab[k] = row.base_color.x, row.base_color.y, row.base_color.z
            er[k], eg[k], eb[k] = row.emission.x, row.emission.y, row.emission.z
            two_sided[k] = row.two_sided_emission
            if ti.static(has_general):
                kind[k] = row.kind
            if ti.static(ctx.lane_conductors):
                alpha[k] = alpha_of(row.roughness)
            if ti.static(aovs):
                albedo = row.base_color
                if ti.static(ctx.lane_conductors):  # a measured metal's: its head-on reflectance
                    if row.complex_ior == 1:
                        albedo = head_on_reflectance(row.eta, row.k)
                albedo_r[k], albedo_g[k], albedo_b[k] = albedo.x, albedo.y, albedo.z
        # emission found by the ray
        emits = live & mask((cos_o > 0.0) | (two_sided != 0)) & mask(ti.max(er, ti.max(eg, eb)) > 0.0)
        if any_lane(emits):
            weight = zero + 1.0
            if ti.static(light_sampling):
                wx, wy, wz = px - prev_x, py - prev_y, pz - prev_z
                dist2 = wx * wx + wy * wy + wz * wz
                cos_l = (wx * nx + wy * ny + wz * nz) / ti.sqrt(ti.max(dist2, 1e-30))
                light_pdf = ctx.lights.pdf_hit(prim, dist2, cos_l, prev_x, prev_y, prev_z)
                sampled = (prev_delta == 0) & (light_pdf > 0.0)
                if ti.static(use_mis):
                    weight = ti.select(sampled, power_heuristic(prev_pdf, light_pdf), 1.0)
                else:
                    weight = ti.select(sampled, 0.0, 1.0)
            lr += ti.select(emits == 1, tr * weight * er, 0.0)
            lg += ti.select(emits == 1, tg * weight * eg, 0.0)
            lb += ti.select(emits == 1, tb * weight * eb, 0.0)
        general = live * 0
        conductor = live * 0  # rough conductors shaded as lanes
        if ti.static(ctx.lane_conductors):
            conductor = live & mask(kind == CONDUCTOR) & mask(alpha > 0.0)
        if ti.static(has_general):
            # every lane where the program takes surface records (which only the scalar code reads)
            general = live if ti.static(ctx.surface_records) else live & mask(kind != DIFFUSE) & (1 - conductor)
        # The last vertex ends the path here, or once its open AOVs are known (below)
        last = max_depth >= 0 and bounces + 1 >= max_depth
        if last:
            if ti.static(aovs):
                if not any_lane(live & aov_open):
                    break
            else:
                break
        # the Lambert lobe about the shading normal on wo's side
        fx, fy, fz = lambert.lobe_normal(snx, sny, snz, cos_o)
        # the next direction's numbers; a Lambert lane's direction, cosine-weighted about its side's
        # normal (not computed where surface records send every lane to the scalar BSDF)
        v1, v2 = uniform2(key, dim + dims.BSDF_DIRECTION)
        bx, by, bz = zero, zero, zero
        weight_r, weight_g, weight_b = ar, ag, ab
        next_pdf = zero
        next_valid = live * 0
        next_delta = live * 0
        if ti.static(not ctx.surface_records):
            bx, by, bz, next_pdf, next_valid = lambert.sample(v1, v2, fx, fy, fz, snx, sny, snz, nx, ny, nz, -dx,
                                                              -dy, -dz)
        # the light sample (none at the last vertex)
        wx, wy, wz, pdf, qx, qy, qz, qnx, qny, qnz, rr, rg, rb = zero, zero, zero, zero, zero, zero, zero, zero, zero, \
            zero, zero, zero, zero
        light = prim_none
        cos_i = zero
        bsdf_pdf = zero
        usable = live * 0
        if ti.static(light_sampling):
            if not last:
                u1, u2 = uniform2(key, dim + dims.LIGHT_POINT)
                wx, wy, wz, dist, pdf, qx, qy, qz, qnx, qny, qnz, rr, rg, rb, light = ctx.lights.sample(
                    px, py, pz, uniform(key, dim + dims.LIGHT_SELECT), u1, u2)
                cos_i, bsdf_pdf, usable = lambert.toward(wx, wy, wz, fx, fy, fz, snx, sny, snz, nx, ny, nz, -dx, -dy,
                                                         -dz)
        # General lanes: f cos toward the light (Lambert lanes' is albedo * cos_i / pi), their own
        # sample, and what their AOVs are
        gr, gg, gb = zero, zero, zero
        shading_x, shading_y, shading_z = snx, sny, snz
        smooth = live
        if ti.static(has_general):
            if any_lane(general):
                gr, gg, gb, bsdf_pdf, usable, bx, by, bz, weight_r, weight_g, weight_b, next_pdf, next_valid, \
                    next_delta, g_albedo_r, g_albedo_g, g_albedo_b, g_x, g_y, g_z, g_smooth = _general_lanes(
                        ctx, ti.static(light_sampling), last, key, dim, general, ox, oy, oz, t, b1, b2, prim, cone,
                        spread, px, py, pz, nx, ny, nz, snx, sny, snz, dx, dy, dz, material, wx, wy, wz, v1, v2,
                        bsdf_pdf, usable, bx, by, bz, weight_r, weight_g, weight_b, next_pdf, next_valid, next_delta)
                is_general = general == 1
                albedo_r = ti.select(is_general, g_albedo_r, albedo_r)
                albedo_g = ti.select(is_general, g_albedo_g, albedo_g)
                albedo_b = ti.select(is_general, g_albedo_b, albedo_b)
                shading_x = ti.select(is_general, g_x, shading_x)
                shading_y = ti.select(is_general, g_y, shading_y)
                shading_z = ti.select(is_general, g_z, shading_z)
                smooth = ti.select(is_general, g_smooth, smooth)
        if ti.static(ctx.lane_conductors):
            if not last and any_lane(conductor):
                is_conductor = conductor == 1
                if ti.static(light_sampling):
                    cr, cg, cb, c_pdf = conductor_lanes.toward(ctx.materials.table, ctx.bsdf.energy, material, alpha,
                                                               wx, wy, wz, fx, fy, fz, snx, sny, snz, nx, ny, nz, -dx,
                                                               -dy, -dz)
                    gr, gg, gb = ti.select(is_conductor, cr, gr), ti.select(is_conductor, cg, gg), \
                        ti.select(is_conductor, cb, gb)
                    bsdf_pdf = ti.select(is_conductor, c_pdf, bsdf_pdf)
                    usable = ti.select(is_conductor, mask(ti.max(cr, ti.max(cg, cb)) > 0.0), usable)
                cx, cy, cz, cwr, cwg, cwb, c_next_pdf, c_valid = conductor_lanes.sample(
                    ctx.materials.table, ctx.bsdf.energy, material, alpha, uniform(key, dim + dims.BSDF_LOBE), v1, v2,
                    fx, fy, fz, snx, sny, snz, nx, ny, nz, -dx, -dy, -dz)
                bx, by, bz = ti.select(is_conductor, cx, bx), ti.select(is_conductor, cy, by), \
                    ti.select(is_conductor, cz, bz)
                weight_r, weight_g, weight_b = (ti.select(is_conductor, cwr, weight_r),
                                                ti.select(is_conductor, cwg, weight_g),
                                                ti.select(is_conductor, cwb, weight_b))
                next_pdf = ti.select(is_conductor, c_next_pdf, next_pdf)
                next_valid = ti.select(is_conductor, c_valid, next_valid)
                next_delta = ti.select(is_conductor, 0, next_delta)
        if ti.static(aovs):
            # the first vertex with a smooth part closes the AOVs; a delta vertex stands in until then
            here = (live == 1) & (aov_open == 1)
            aov_r = ti.select(here, aov_wr * albedo_r, aov_r)
            aov_g = ti.select(here, aov_wg * albedo_g, aov_g)
            aov_b = ti.select(here, aov_wb * albedo_b, aov_b)
            aov_nx, aov_ny, aov_nz = (ti.select(here, shading_x, aov_nx), ti.select(here, shading_y, aov_ny),
                                      ti.select(here, shading_z, aov_nz))
            aov_open = ti.select(here & (smooth == 1), 0, aov_open)
        if last:
            break
        if ti.static(light_sampling):
            scale = zero + 1.0 / ti.max(pdf, 1e-30)
            if ti.static(use_mis):
                scale *= power_heuristic(pdf, bsdf_pdf)
            found = live & mask((pdf > 0.0) & (ti.max(rr, ti.max(rg, rb)) > 0.0)) & usable
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
                blocker, t_blocker, b1_blocker, b2_blocker, sv, st = prim_none, zero, zero, zero, zero, zero
                if ti.static(ctx.scalar_bounces):
                    blocker, t_blocker, b1_blocker, b2_blocker, sv, st = traversal.trace_lanes(
                        geometry, sx, sy, sz, gx, gy, gz, t_max, True)
                else:
                    blocker, t_blocker, b1_blocker, b2_blocker, psv, pst = traversal.trace(
                        geometry, sx, sy, sz, gx, gy, gz, t_max, True)
                    sv, st = zero + psv, zero + pst
                took = ti.cast(mask(t_max >= 0.0), ti.f32)
                occupancy += ti.math.ivec4(0, 0, 1, mask(t_max >= 0.0).sum())
                visits += took * sv
                tests += took * st
                rays += took
                add = (t_max >= 0.0) & (blocker < 0)
                f = cos_i * INV_PI * scale
                if ti.static(has_general):
                    is_general = (general | conductor) == 1  # their f cos is in g (rgb)
                    lr += ti.select(add, tr * ti.select(is_general, gr * scale, ar * f) * rr, 0.0)
                    lg += ti.select(add, tg * ti.select(is_general, gg * scale, ag * f) * rg, 0.0)
                    lb += ti.select(add, tb * ti.select(is_general, gb * scale, ab * f) * rb, 0.0)
                else:
                    lr += ti.select(add, tr * ar * f * rr, 0.0)
                    lg += ti.select(add, tg * ag * f * rg, 0.0)
                    lb += ti.select(add, tb * ab * f * rb, 0.0)
        # the next direction
        live &= next_valid
        tr, tg, tb = tr * weight_r, tg * weight_g, tb * weight_b
        if ti.static(aovs):
            still = (live == 1) & (aov_open == 1)
            aov_wr, aov_wg, aov_wb = (ti.select(still, aov_wr * weight_r, aov_wr),
                                      ti.select(still, aov_wg * weight_g, aov_wg),
                                      ti.select(still, aov_wb * weight_b, aov_wb))
        prev_x, prev_y, prev_z = px, py, pz
        if ti.static(ctx.filters_textures):
            cone = cone + spread * t  # the next ray's cone starts as wide as this one arrived (Surface.cone_width)
        prev_pdf = next_pdf
        prev_delta = next_delta
        ox, oy, oz = leave(px, py, pz, nx, ny, nz, eps, bx * nx + by * ny + bz * nz)
        dx, dy, dz = bx, by, bz
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
    return lr, lg, lb, visits, tests, rays, occupancy, seeds, (aov_r, aov_g, aov_b, aov_nx, aov_ny, aov_nz)

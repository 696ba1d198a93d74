"""`nee` and `mis`: path tracing with direct light sampling at every vertex.

`nee` takes direct light from light samples only: a BSDF-sampled ray that lands on an emitter the
lights can sample adds nothing (that light was counted already), except after a delta bounce,
which light sampling cannot follow. `mis` counts both strategies, each weighted by the power
heuristic (Veach 1997), so whichever samples a light better dominates: light sampling for small
lights and diffuse surfaces, BSDF sampling for large lights and glossy surfaces.
Emitters the lights cannot sample (SDF shapes other than spheres) are found by BSDF sampling alone,
at full weight, in both.
"""
import taichi as ti

from renderer.geometry.interface import INF, Hit, Surface
from renderer.integrators.path import MAX_VERTICES, RR_DEPTH
from renderer.sampling import dims

vec3 = ti.math.vec3


@ti.func
def power_heuristic(a, b):
    """a^2 / (a^2 + b^2), written through the ratio of the smaller to the larger density so that
    an infinite or overflowing density (a light seen exactly edge-on) gives 1 or 0, never inf/inf."""
    w = 0.0
    if a >= b and a > 0.0:
        r = b / a
        w = 1.0 / (1.0 + r * r)
    elif b > a:
        r = a / b
        w = r * r / (1.0 + r * r)
    return w


@ti.data_oriented
class DirectLightingPathTracer:
    uses_lights = True
    display_tonemapper = None
    mis = True

    @ti.func
    def li(self, ctx, ray_in, state, max_depth):
        """One loop traces every ray of the path, shadow rays included, at a single call site of
        the geometry: each call site of a traversal or of an SDF is compiled in again, and the
        two-site form compiled to a kernel 2.6 times the size of `path`'s.

        A vertex that samples a light leaves its shadow ray pending: the next iteration traces it
        (adding the light's contribution if nothing blocks it), and the one after traces the
        BSDF-sampled continuation from the same vertex."""
        radiance = vec3(0.0)
        throughput = vec3(1.0)
        ray = ray_in
        stats = vec3(0.0)
        lights = ctx.lights
        prev_p = ray.o
        prev_n = vec3(0.0)
        prev_pdf = 0.0
        prev_delta = 1  # the camera: what it sees directly is not light-sampled
        s = Surface(p=ray.o, n_geo=vec3(0.0, 0.0, 1.0), n_shading=vec3(0.0, 0.0, 1.0), uv=ti.math.vec2(0.0),
                    uv1=ti.math.vec2(0.0), tangent=ti.math.vec4(0.0), material=0, prim=-1, front_face=1, eps=0.0,
                    cone_width=0.0, cone_spread=0.0)
        next_dir = ray.d
        shadow_pending = False
        shadow_target = vec3(0.0)
        shadow_n = vec3(0.0)
        shadow_value = vec3(0.0)
        ending = False  # the path is over once its pending shadow ray is traced
        depth = 0
        for _ in range(2 * MAX_VERTICES):
            t_max = INF
            if depth > 0:
                ray, t_max = ctx.geometry.next_segment(s, next_dir, shadow_target, shadow_n, shadow_pending)
            hit = Hit(hit=0, t=t_max, work=0, tests=0, inside=0, prim=-1, bary=ti.math.vec2(0.0))
            if t_max > 0.0:
                hit = ctx.geometry.intersect(ray, t_max)
                stats += vec3(hit.work, hit.tests, 1.0)
            if shadow_pending:
                if hit.hit == 0:
                    radiance += shadow_value
                shadow_pending = False
                if ending:
                    break
                continue
            if hit.hit == 0:
                weight = 1.0
                if ti.static(lights.has_env):
                    if prev_delta == 0:
                        if ti.static(self.mis):
                            weight = power_heuristic(prev_pdf, lights.pdf_env(ray.d))
                        else:
                            weight = 0.0
                radiance += throughput * weight * ctx.environment.radiance(ray.d)
                break
            s = ctx.geometry.surface(ray, hit)
            wo = -ray.d
            mat, n = ctx.bsdf.shade(s, wo)
            if ti.static(ctx.features.has_emission):
                if s.front_face == 1 and mat.emission.max() > 0.0:
                    weight = 1.0
                    if prev_delta == 0 and lights.is_sampled(s.prim):
                        if ti.static(self.mis):
                            weight = power_heuristic(prev_pdf, lights.pdf_hit(prev_p, prev_n, s.prim, s.p, s.n_geo))
                        else:
                            weight = 0.0
                    radiance += throughput * weight * mat.emission
            if max_depth >= 0 and depth + 1 >= max_depth:
                break
            dim = dims.BOUNCE_BASE + dims.PER_BOUNCE * depth
            if ctx.bsdf.has_smooth_part(mat):
                ls = lights.sample(ctx, s.p, n, ctx.sampler.get1d(state, dim + dims.LIGHT_SELECT),
                                   ctx.sampler.get2d(state, dim + dims.LIGHT_POINT))
                if ls.pdf > 0.0 and ls.radiance.max() > 0.0:
                    f, pdf_bsdf = ctx.bsdf.eval_at(mat, n, s.n_geo, wo, ls.wi)
                    if f.max() > 0.0:
                        # An environment sample's point lies far away: area lights and the
                        # environment share the shadow ray.
                        weight = 1.0
                        if ti.static(self.mis):
                            weight = power_heuristic(ls.pdf, pdf_bsdf)
                        shadow_pending = True
                        shadow_target = ls.p
                        shadow_n = ls.n
                        shadow_value = throughput * f * ls.radiance * (weight / ls.pdf)
            bs = ctx.bsdf.sample_at(mat, n, s.n_geo, wo, ctx.sampler.get1d(state, dim + dims.BSDF_LOBE),
                                    ctx.sampler.get2d(state, dim + dims.BSDF_DIRECTION))
            if bs.valid == 0:
                ending = True
            else:
                throughput *= bs.weight
                prev_p = s.p
                prev_n = n
                prev_pdf = bs.pdf
                prev_delta = bs.delta
                if depth >= RR_DEPTH:
                    q = ti.min(throughput.max(), 0.95)
                    if ctx.sampler.get1d(state, dim + dims.ROULETTE) >= q:
                        ending = True
                    else:
                        throughput /= q
                next_dir = bs.wi
            if ending and not shadow_pending:
                break
            depth += 1
        return radiance, stats


@ti.data_oriented
class NextEventEstimation(DirectLightingPathTracer):
    name = "nee"
    hotkey = "j"  # next to "k" (mis)
    description = "path tracing with light sampling for direct light"
    mis = False


@ti.data_oriented
class MultipleImportanceSampling(DirectLightingPathTracer):
    name = "mis"
    hotkey = "k"
    description = "light and BSDF sampling combined by the power heuristic (the default)"
    mis = True

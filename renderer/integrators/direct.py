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

from renderer.geometry.interface import INF
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
        radiance = vec3(0.0)
        throughput = vec3(1.0)
        ray = ray_in
        stats = vec3(0.0)
        lights = ctx.lights
        prev_p = ray.o
        prev_n = vec3(0.0)
        prev_pdf = 0.0
        prev_delta = 1  # the camera: what it sees directly is not light-sampled
        for depth in range(MAX_VERTICES):
            hit = ctx.geometry.intersect(ray, INF)
            stats += vec3(hit.work, hit.tests, 1.0)
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
                        # One shadow-ray call site for area lights and the environment alike (an
                        # environment sample's point lies far away): every call site of a traversal
                        # is compiled in again, so one is much cheaper to compile than two.
                        stats.z += 1.0
                        if ctx.geometry.visible(s, ls.p, ls.n):
                            weight = 1.0
                            if ti.static(self.mis):
                                weight = power_heuristic(ls.pdf, pdf_bsdf)
                            radiance += throughput * f * ls.radiance * (weight / ls.pdf)
            bs = ctx.bsdf.sample_at(mat, n, s.n_geo, wo, ctx.sampler.get1d(state, dim + dims.BSDF_LOBE),
                                 ctx.sampler.get2d(state, dim + dims.BSDF_DIRECTION))
            if bs.valid == 0:
                break
            throughput *= bs.weight
            prev_p = s.p
            prev_n = n
            prev_pdf = bs.pdf
            prev_delta = bs.delta
            if depth >= RR_DEPTH:
                q = ti.min(throughput.max(), 0.95)
                if ctx.sampler.get1d(state, dim + dims.ROULETTE) >= q:
                    break
                throughput /= q
            ray = ctx.geometry.spawn(s, bs.wi)
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

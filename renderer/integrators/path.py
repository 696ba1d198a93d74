"""`path`: unidirectional path tracing with BSDF sampling only, and Russian roulette."""
import taichi as ti

from renderer.geometry.interface import INF
from renderer.sampling import dims

# Hard cap on path vertices when max_depth is -1 (unlimited): Russian roulette ends paths long
# before this; the cap only bounds the loop (GPU back-ends need a bounded loop to be safe).
MAX_VERTICES = 1024
# Russian roulette starts after this many bounces (Mitsuba's default rr_depth is 5).
RR_DEPTH = 5


@ti.data_oriented
class PathTracer:
    name = "path"
    hotkey = "t"  # "trace"
    description = "path tracing, BSDF sampling only"
    display_tonemapper = None

    @ti.func
    def li(self, ctx, ray_in, state, max_depth):
        radiance = ti.math.vec3(0.0)
        throughput = ti.math.vec3(1.0)
        ray = ray_in
        stats = ti.math.vec3(0.0)
        for depth in range(MAX_VERTICES):
            hit = ctx.geometry.intersect(ray, INF)
            stats += ti.math.vec3(hit.work, hit.tests, 1.0)
            if hit.hit == 0:
                radiance += throughput * ctx.environment.radiance(ray.d)
                break
            s = ctx.geometry.surface(ray, hit)
            mat, n_shading = ctx.bsdf.shade(s, -ray.d)
            if ti.static(ctx.features.has_emission):
                if s.front_face == 1:
                    radiance += throughput * mat.emission
            # Mitsuba's convention: max_depth counts path vertices, 1 = emitters seen directly.
            if max_depth >= 0 and depth + 1 >= max_depth:
                break
            dim = dims.BOUNCE_BASE + dims.PER_BOUNCE * depth
            bs = ctx.bsdf.sample_at(mat, n_shading, s.n_geo, -ray.d, ctx.sampler.get1d(state, dim + dims.BSDF_LOBE),
                                 ctx.sampler.get2d(state, dim + dims.BSDF_DIRECTION))
            if bs.valid == 0:
                break
            throughput *= bs.weight
            if depth >= RR_DEPTH:
                q = ti.min(throughput.max(), 0.95)
                if ctx.sampler.get1d(state, dim + dims.ROULETTE) >= q:
                    break
                throughput /= q
            ray = ctx.geometry.spawn(s, bs.wi)
        return radiance, stats

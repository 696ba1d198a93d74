"""Debug views: what the first hit is, not how it is lit. One ray per sample.

They write no denoising AOVs (zeros): their images are not noisy estimates of light."""
import taichi as ti

from renderer.geometry.interface import INF

vec3 = ti.math.vec3


@ti.func
def heat(x):
    """A perceptually ordered black-purple-orange-yellow ramp for x in [0, 1]."""
    t = ti.math.clamp(x, 0.0, 1.0) * 4.0
    c0 = vec3(0.0, 0.0, 0.02)
    c1 = vec3(0.34, 0.06, 0.43)
    c2 = vec3(0.73, 0.21, 0.33)
    c3 = vec3(0.98, 0.55, 0.04)
    c4 = vec3(0.99, 1.0, 0.64)
    c = c0
    if t < 1.0:
        c = ti.math.mix(c0, c1, t)
    elif t < 2.0:
        c = ti.math.mix(c1, c2, t - 1.0)
    elif t < 3.0:
        c = ti.math.mix(c2, c3, t - 2.0)
    else:
        c = ti.math.mix(c3, c4, t - 3.0)
    return c


@ti.func
def view_sample(value, hit):
    """What a debug view's li returns: its value, the ray's work statistics, no AOVs."""
    return value, vec3(hit.work, hit.tests, 1.0), vec3(0.0), vec3(0.0)


@ti.data_oriented
class NormalsView:
    name = "normals"
    hotkey = "o"  # "orientation"
    description = "shading normal at the first hit, mapped to [0, 1]"
    display_tonemapper = "none"
    writes_aovs = False
    denoisable = False

    @ti.func
    def li(self, ctx, ray, state, max_depth):
        hit = ctx.geometry.intersect(ray, INF)
        value = vec3(0.0)
        if hit.hit == 1:
            _, n = ctx.bsdf.shade(ctx.geometry.surface(ray, hit), -ray.d)  # normal maps included
            value = n * 0.5 + 0.5
        return view_sample(value, hit)


@ti.data_oriented
class AlbedoView:
    name = "albedo"
    hotkey = "c"  # "colour"
    description = "base colour at the first hit"
    display_tonemapper = "none"
    writes_aovs = False
    denoisable = False

    @ti.func
    def li(self, ctx, ray, state, max_depth):
        hit = ctx.geometry.intersect(ray, INF)
        value = vec3(0.0)
        if hit.hit == 1:
            mat, _ = ctx.bsdf.shade(ctx.geometry.surface(ray, hit), -ray.d)
            value = ctx.bsdf.albedo(mat)
        return view_sample(value, hit)


@ti.data_oriented
class DepthView:
    name = "depth"
    hotkey = "z"  # "z-buffer"
    description = "distance to the first hit in metres (0 for misses); shown as d / (1 + d)"
    display_tonemapper = "reinhard"
    writes_aovs = False
    denoisable = False

    @ti.func
    def li(self, ctx, ray, state, max_depth):
        hit = ctx.geometry.intersect(ray, INF)
        value = vec3(0.0)
        if hit.hit == 1:
            value = vec3(hit.t)
        return view_sample(value, hit)


@ti.data_oriented
class StepsView:
    name = "steps"
    hotkey = "g"  # "geometry work"
    description = "geometry work per camera ray (march steps) as a heat map of work / 256"
    display_tonemapper = "none"
    writes_aovs = False
    denoisable = False

    @ti.func
    def li(self, ctx, ray, state, max_depth):
        hit = ctx.geometry.intersect(ray, INF)
        # 256 is the default step limit: the ramp saturates where rays give up.
        return view_sample(heat(hit.work / 256.0), hit)


@ti.data_oriented
class BvhView:
    name = "bvh"
    hotkey = "v"  # "visits"
    description = "BVH node visits (red) and primitive tests (green) per camera ray, as fractions of 128"
    display_tonemapper = "none"
    writes_aovs = False
    denoisable = False

    @ti.func
    def li(self, ctx, ray, state, max_depth):
        hit = ctx.geometry.intersect(ray, INF)
        # 128 visits or tests is a deep, costly ray for a tree with leaves of 4: the scale saturates there.
        value = vec3(ti.min(hit.work / 128.0, 1.0), ti.min(hit.tests / 128.0, 1.0), 0.0)
        if hit.hit == 1:
            value.z = 0.25  # a hint of blue shows where the ray found a surface
        return view_sample(value, hit)

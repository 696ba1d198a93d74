"""Debug views: what the first hit is, not how it is lit. One ray per sample.

A view is one row of VIEWS: its name, the viewer's letter for it, a description, the tone mapper
its output wants, and the Taichi func giving a camera ray's value from its first hit. DebugView
runs any row; the row's func is resolved while Taichi compiles, so each view's kernel holds only
its own code.

They write no denoising AOVs (zeros): their images are not noisy estimates of light."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

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


# --- what each view shows of the first hit ------------------------------------------------------


@ti.func
def shading_normal(ctx, ray, hit):
    value = vec3(0.0)
    if hit.hit == 1:
        _, n = ctx.bsdf.shade(ctx.geometry.surface(ray, hit), -ray.d)  # normal maps included
        value = n * 0.5 + 0.5
    return value


@ti.func
def base_colour(ctx, ray, hit):
    value = vec3(0.0)
    if hit.hit == 1:
        mat, _ = ctx.bsdf.shade(ctx.geometry.surface(ray, hit), -ray.d)
        value = ctx.bsdf.albedo(mat)
    return value


@ti.func
def hit_distance(ctx, ray, hit):
    value = vec3(0.0)
    if hit.hit == 1:
        value = vec3(hit.t)
    return value


@ti.func
def march_steps(ctx, ray, hit):
    # 256 is the default step limit: the ramp saturates where rays give up.
    return heat(hit.work / 256.0)


@ti.func
def bvh_work(ctx, ray, hit):
    # 128 visits or tests is a deep, costly ray for a tree with leaves of 4: the scale saturates there.
    value = vec3(ti.min(hit.work / 128.0, 1.0), ti.min(hit.tests / 128.0, 1.0), 0.0)
    if hit.hit == 1:
        value.z = 0.25  # a hint of blue shows where the ray found a surface
    return value


# --- the views -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class DebugViewRow:
    """One debug view, as the integrator registry lists it: the attributes every integrator has
    (renderer/integrators/__init__.py), and calling it makes the view's integrator."""

    name: str
    hotkey: str
    description: str
    display_tonemapper: str
    value: Callable  # a Taichi func (ctx, ray, hit) -> vec3
    writes_aovs = False
    denoisable = False

    def __call__(self) -> DebugView:
        return DebugView(self)


# The letters stand for orientation, colour, z-buffer, geometry work and visits.
VIEWS = (
    DebugViewRow("normals", "o", "shading normal at the first hit, mapped to [0, 1]", "none", shading_normal),
    DebugViewRow("albedo", "c", "base colour at the first hit", "none", base_colour),
    DebugViewRow("depth", "z", "distance to the first hit in metres (0 for misses); shown as d / (1 + d)",
                 "reinhard", hit_distance),
    DebugViewRow("steps", "g", "geometry work per camera ray (march steps) as a heat map of work / 256", "none",
                 march_steps),
    DebugViewRow("bvh", "v", "BVH node visits (red) and primitive tests (green) per camera ray, as fractions of "
                 "128", "none", bvh_work),
)


@ti.data_oriented
class DebugView:
    """The integrator of one debug view: the first hit of the camera ray, shown as its row says."""

    def __init__(self, row: DebugViewRow):
        self.row = row
        self.name = row.name
        self.hotkey = row.hotkey
        self.description = row.description
        self.display_tonemapper = row.display_tonemapper
        self.writes_aovs = row.writes_aovs
        self.denoisable = row.denoisable

    @ti.func
    def li(self, ctx, ray, state, max_depth):
        """The view's value, the ray's work statistics, no AOVs."""
        hit = ctx.geometry.intersect(ray, INF)
        return self.row.value(ctx, ray, hit), vec3(hit.work, hit.tests, 1.0), vec3(0.0), vec3(0.0)

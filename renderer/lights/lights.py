"""Every emitter of a scene for direct lighting: emissive primitives (chosen by a light selector,
then a point on the chosen one), the environment (importance-sampled map, or uniform directions
for a sky or constant colour), and lights without a surface (point, spot, directional:
renderer/lights/delta_lights.py).

  sample(ctx, ref, ref_n, u_select, u_point) -> LightSample    one light, one point, its radiance
  pdf_hit(ref, ref_n, prim, p, n) -> f32    density of `sample` giving point p on primitive prim
  pdf_env(direction) -> f32                 density of `sample` giving that environment direction
All densities are per unit solid angle at `ref` and include the choice of the light, so MIS
weights can compare them with BSDF densities directly. Emitters are one-sided (Lambertian, like
Mitsuba's area lights): they emit from the side their normal faces, or from both where their
material says so (`two_sided_emission`, pbrt's twosided area lights).

A sample of a light without a surface has `delta` = 1: its `pdf` is only the probability of
choosing that light, its `radiance` the value that multiplies f / pdf (I falloff / r^2 or E), and
it takes no MIS weight (no BSDF sample can find it). Where a scene has such lights, the samples
not given to the environment are split between them and the emissive primitives in proportion to
their peak intensities (`delta_share`).
"""
import math

import numpy as np
import taichi as ti

from renderer.geometry.interface import INF, Surface
from renderer.lights.env_sampling import EnvironmentSampler
from renderer.lights.light_select import make_light_selector
from renderer.lights.light_tree_build import EmitterBounds
from renderer.spectral.luminance import LUMINANCE_WEIGHTS
from renderer.sampling.warps import PI
from renderer.runtime.upload import upload_fields

vec3 = ti.math.vec3
LightSample = ti.types.struct(wi=vec3, dist=ti.f32, radiance=vec3, pdf=ti.f32, p=vec3, n=vec3, is_env=ti.i32,
                              delta=ti.i32)

# Where an environment sample's "point" is placed, so that one shadow-ray routine serves every
# light: far beyond any scene this renderer is meant for (1e4 km), near enough for f32 directions.
ENV_DISTANCE = 1e7
# The share of light samples given to the environment when the scene also has emissive
# primitives: half, since neither's contribution is known before rendering.
ENVIRONMENT_SHARE = 0.5


def environment_emits(spec) -> bool:
    if spec.intensity <= 0.0:
        return False
    if spec.kind == "constant":
        return max(spec.color) > 0.0
    return True


@ti.func
def emitted_radiance(ctx, geometry, g, p, n, uv, w):
    """The radiance emissive primitive g emits at p towards w (textured emission included)."""
    surface = Surface(p=p, n_geo=n, n_shading=n, uv=uv, uv1=uv, tangent=ti.math.vec4(0.0),
                      material=geometry.material_of(g), prim=g, front_face=1, eps=0.0,
                      cone_width=0.0, cone_spread=0.0)
    mat, _ = ctx.bsdf.shade(surface, w)
    return mat.emission


@ti.func
def choose_environment(has_env: ti.template(), share, u):
    """Whether a light (or photon) comes from the environment, chosen with probability `share`,
    and u remapped to [0, 1) within the chosen side so it can still pick among the emitters."""
    use_env = False
    v = u
    if ti.static(has_env):
        if v < share:
            use_env = True
            v = v / share
        else:
            v = (v - share) / (1.0 - share)
    return use_env, v


@ti.func
def choose_share(share, u):
    """Whether the first of two groups is chosen (probability `share`), and u remapped to [0, 1)
    within the chosen one."""
    first = False
    v = u
    if v < share:
        first = True
        v = v / share
    else:
        v = (v - share) / (1.0 - share)
    return first, v


@ti.func
def environment_direction(source, u):
    """(direction, solid-angle pdf, radiance) towards the environment of `source` (an object with
    env_is_map, env_sampler and environment): importance-sampled on a map, uniform otherwise."""
    d = vec3(0.0, 1.0, 0.0)
    pdf = 0.0
    radiance = vec3(0.0)
    if ti.static(source.env_is_map):
        d, pdf, radiance = source.env_sampler.sample(u)
    else:
        z = 1.0 - 2.0 * u.x
        r = ti.sqrt(ti.max(0.0, 1.0 - z * z))
        phi = 2.0 * PI * u.y
        d = vec3(r * ti.cos(phi), z, r * ti.sin(phi))
        pdf = 1.0 / (4.0 * PI)
        radiance = source.environment.radiance(d)
    return d, pdf, radiance


@ti.data_oriented
class Lights:
    def __init__(self, geometry, emitters: dict, environment, env_spec, env_image, selector_kind="auto",
                 delta=None):
        """emitters: `emitter_table`'s rows (numpy, one per emissive primitive; kept for photon
        emission); env_image: the map for kind "map", else None; delta: the scene's
        `DeltaLights`, or None."""
        self.geometry = geometry
        self.emitters = emitters
        self.environment = environment
        self.count = len(emitters["prim"])
        self.has_area = self.count > 0
        self.has_env = environment_emits(env_spec)
        self.env_is_map = env_spec.kind == "map"
        self.delta = delta
        self.has_delta = delta is not None and delta.count > 0
        others = self.has_area or self.has_delta
        share = ENVIRONMENT_SHARE if (others and self.has_env) else (1.0 if self.has_env else 0.0)
        self.env_share = ti.field(ti.f32, shape=())
        self.env_share[None] = share
        if self.has_delta:
            # The rest between the lights without a surface and the emissive primitives, by the most
            # each sends a point at a given distance: a point light of power P sends P / (4 pi) per
            # sr, a Lambertian emitter of power P at most P / pi. Weighing powers instead would give
            # a point light four times its share of what reaches a point, and starve the surfaces
            # (their rare samples then come with large weights: fireflies).
            self.delta_share = ti.field(ti.f32, shape=())
            self.refit_delta()
        # Emitters that shine from both faces: compiled in only where the scene has one (a lookup
        # per light sample otherwise paid by every scene).
        self.has_two_sided = self.has_area and bool(np.any(emitters.get("two_sided", ())))
        self.emitter_two_sided = ti.field(ti.i32, shape=max(1, self.count))
        if self.has_two_sided:
            upload_fields([(self.emitter_two_sided, np.asarray(emitters["two_sided"], np.int32))])
        prim_total = max(1, geometry.primitive_count())
        self.prim_emitter = ti.field(ti.i32, shape=prim_total)
        self.emitter_prim = ti.field(ti.i32, shape=max(1, self.count))
        lookup = np.full(prim_total, -1, np.int32)
        if self.has_area:
            lookup[emitters["prim"]] = np.arange(self.count, dtype=np.int32)
            bounds = EmitterBounds(lo=emitters["lo"], hi=emitters["hi"], power=emitters["power"], axis=emitters["axis"],
                                   theta_o=emitters["theta_o"], theta_e=emitters["theta_e"])
            self.selector = make_light_selector(selector_kind, bounds)
        upload_fields([(self.prim_emitter, lookup)]
                      + ([(self.emitter_prim, np.asarray(emitters["prim"], np.int32))] if self.has_area else []))
        if self.has_env and self.env_is_map:
            self.env_sampler = EnvironmentSampler(env_image, environment)

    def refit_delta(self) -> None:
        """The share of the lights without a surface, from their intensities and the emitters'
        powers (again after DeltaLights.refit or an emission edit)."""
        delta_intensity = float(self.delta.intensity.sum())
        area_intensity = float(np.sum(self.emitters["power"])) / math.pi if self.has_area else 0.0
        self.delta_share[None] = (delta_intensity / (delta_intensity + area_intensity) if area_intensity > 0.0
                                  else 1.0)

    def refit(self, emitters: dict) -> bool:
        """Take `emitter_table`'s rows for the same emissive primitives with other radiance (an
        emission edit) in place: the selector's weights and the share of the lights without a
        surface, in the same fields, so no kernel compiles. False, nothing changed, where the
        primitives that emit, or their sides, differ: build the Lights anew then."""
        same = (np.array_equal(emitters["prim"], self.emitters["prim"])
                and np.array_equal(emitters["two_sided"], self.emitters["two_sided"]))
        if not same:
            return False
        if self.has_area:
            bounds = EmitterBounds(lo=emitters["lo"], hi=emitters["hi"], power=emitters["power"], axis=emitters["axis"],
                                   theta_o=emitters["theta_o"], theta_e=emitters["theta_e"])
            if not self.selector.refit(bounds):
                return False
        self.emitters = emitters
        if self.has_delta:
            self.refit_delta()
        return True

    @ti.func
    def sample(self, ctx, ref, ref_n, u_select, u_point):
        result = LightSample(wi=vec3(0.0, 0.0, 1.0), dist=INF, radiance=vec3(0.0), pdf=0.0, p=ref, n=vec3(0.0, 0.0, 1.0),
                             is_env=0, delta=0)
        share = self.env_share[None]
        use_env, u = choose_environment(self.has_env, share, u_select)
        if use_env:
            if ti.static(self.has_env):
                d, pdf, radiance = environment_direction(self, u_point)
                result = LightSample(wi=d, dist=INF, radiance=radiance, pdf=pdf * share, p=ref + ENV_DISTANCE * d,
                                     n=-d, is_env=1, delta=0)
        else:
            use_delta = False
            area_share = 1.0
            if ti.static(self.has_delta):
                delta_share = self.delta_share[None]
                area_share = 1.0 - delta_share
                use_delta, u = choose_share(delta_share, u)
                if use_delta:
                    pmf, wi, dist, value, position = self.delta.choose(ctx.features, ref, ref_n,
                                                                       ti.min(u, 0.99999994))
                    p = position
                    if dist == INF:  # directional: the shadow ray's end far away, as the environment's
                        p = ref + ENV_DISTANCE * wi
                    result = LightSample(wi=wi, dist=dist, radiance=value, pdf=pmf * delta_share * (1.0 - share),
                                         p=p, n=-wi, is_env=0, delta=1)
            if ti.static(self.has_area):
                if not use_delta:
                    e, pmf = self.selector.select(ref, ref_n, ti.min(u, 0.99999994))
                    g = self.emitter_prim[e]
                    pt = self.geometry.sample_emitter(g, ref, u_point)
                    to = pt.p - ref
                    dist = to.norm()
                    if pt.pdf > 0.0 and dist > 0.0:
                        wi = to / dist
                        radiance = vec3(0.0)
                        faces_ref = pt.n.dot(wi) < 0.0  # the emitting (front) side faces ref
                        if ti.static(self.has_two_sided):
                            faces_ref = faces_ref or self.emitter_two_sided[e] == 1
                        if faces_ref:
                            radiance = emitted_radiance(ctx, self.geometry, g, pt.p, pt.n, pt.uv, -wi)
                        pdf = pt.pdf * pmf * (1.0 - share)
                        if ti.static(self.has_delta):
                            pdf *= area_share
                        result = LightSample(wi=wi, dist=dist, radiance=radiance, pdf=pdf, p=pt.p, n=pt.n, is_env=0,
                                             delta=0)
        return result

    @ti.func
    def pdf_hit(self, ref, ref_n, g, p, n):
        pdf = 0.0
        if ti.static(self.has_area):
            e = self.prim_emitter[g]
            if e >= 0:
                pdf = self.selector.pmf(ref, ref_n, e) * (1.0 - self.env_share[None]) * self.geometry.emitter_pdf(g, ref, p, n)
                if ti.static(self.has_delta):
                    pdf *= 1.0 - self.delta_share[None]
        return pdf

    @ti.func
    def is_sampled(self, g):
        sampled = False
        if ti.static(self.has_area):
            sampled = self.prim_emitter[g] >= 0
        return sampled

    @ti.func
    def pdf_env(self, d):
        pdf = 0.0
        if ti.static(self.has_env):
            if ti.static(self.env_is_map):
                pdf = self.env_sampler.pdf(d)
            else:
                pdf = 1.0 / (4.0 * PI)
            pdf *= self.env_share[None]
        return pdf


def emitter_table(geometry, rows_arrays: dict) -> dict:
    """The emissive primitives the geometry can sample, with the data light selection needs."""
    info = geometry.emitter_info()
    emission = rows_arrays["emission"][info["material"]] if len(info["prim"]) else np.zeros((0, 3))
    luminance = emission @ np.array(LUMINANCE_WEIGHTS)
    keep = luminance > 0.0
    two_sided = (rows_arrays["two_sided_emission"][info["material"]] != 0 if len(info["prim"])
                 else np.zeros(0, bool))[keep]
    # Flux of a one-sided Lambertian emitter: radiance x area x pi; twice that from both faces,
    # whose normals then span every direction (theta_o pi for the light tree).
    power = luminance[keep] * info["area"][keep] * math.pi * np.where(two_sided, 2.0, 1.0)
    theta_o = np.where(two_sided, math.pi, info["theta_o"][keep])
    return {"prim": info["prim"][keep], "power": power, "area": info["area"][keep], "lo": info["lo"][keep],
            "hi": info["hi"][keep], "axis": info["axis"][keep], "theta_o": theta_o,
            "theta_e": info["theta_e"][keep], "two_sided": two_sided}

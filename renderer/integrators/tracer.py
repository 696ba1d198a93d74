"""The unidirectional path tracer behind `path`, `nee` and `mis`, with participating media.

Static switches pick the estimator: `light_sampling` (next-event estimation at every vertex) and
`mis` (BSDF- and light-sampled contributions combined by the power heuristic, Veach 1997; without
it, emitters the lights can sample count only through light samples, except after a delta
bounce, which light sampling cannot follow). Emitters the lights cannot sample (SDF shapes other
than spheres) are found by BSDF sampling alone, at full weight; point, spot and directional lights
(renderer/lights/delta_lights.py), which no ray can hit, by light samples alone, at full weight, so
`path` never sees them.

One loop traces every ray of the path, shadow rays included, at a single call site of the
geometry: every call site of a traversal or of an SDF is compiled in again (the two-site form of
`mis` compiled to a kernel 2.6 times the size of `path`'s). A vertex that samples a light leaves
its shadow ray pending; the next iteration traces it (adding the light if nothing blocks it), and
the one after traces the BSDF-sampled continuation from the same vertex.

Media (compiled only for scenes with them, Features.has_media): a path knows the medium it is in
(the scene's fog medium to start with; a material's `medium` after crossing into its surface).
Along each segment a free-flight distance is sampled (spectral MIS over RGB); a scattering event
before the surface is a vertex with the Henyey-Greenstein phase function in place of a BSDF,
light-sampled like any other. Shadow rays carry the transmittance of their medium and pass
through `null` surfaces and smooth thin dielectrics (times the wall's transmittance), switching
medium; any other surface blocks them. Media do not nest: crossing out of a surface leads to its
material's outside medium, the scene's unless named (pbrt's MediumInterface). As in Mitsuba, a smooth thin wall's straight passage is like a null crossing
(no bounce, and MIS keeps the vertex before it), and a thin wall that bounds a medium of its own
is entered like any other boundary. Grid media (Features.has_grid_media,
renderer/media/grid.py) sample the free flight by delta tracking and the shadow rays'
transmittance by ratio tracking, each segment from a hashed stream of its own.

Dispersion (Features.has_dispersion): a path is RGB until it first meets a dispersive dielectric.
There it draws one wavelength (visible-importance pdf) and becomes spectral: its throughput turns
into the sensor's RGB response at that wavelength over the pdf, times the spectral value of what
it carried (RGB upsampled to a spectrum, white exactly 1), and every later colour (BSDF weights,
emission, environment, lights, media) enters as its spectral value at that wavelength; dispersive
surfaces refract with their index at that wavelength. One wavelength per path rather than a hero
set of four: simpler, at the price of more colour noise behind dispersive glass.
"""
import taichi as ti

from renderer.geometry.interface import INF, MEDIUM_POINT, Hit, Surface
from renderer.integrators.light_sampling import emission_weight, environment_weight, light_weight, sample_direct
from renderer.materials import dispersion, lobes
from renderer.materials.kinds import KIND_IDS, NULL_KIND, SCENE_MEDIUM
from renderer.materials.table import NO_MEDIUM
from renderer.media import grid, homogeneous, phase
from renderer.sampling import dims
from renderer.spectral.cie import spectral_rgb_weights
from renderer.spectral.upsample import rgb_to_spectrum
from renderer.spectral.wavelengths import sample_visible_wavelength, visible_wavelength_pdf

vec3 = ti.math.vec3

# Hard cap on path vertices when max_depth is -1 (unlimited): Russian roulette ends paths long
# before this; the cap only bounds the loop (GPU back-ends need a bounded loop to be safe).
MAX_VERTICES = 1024
# Russian roulette starts after this many bounces (Mitsuba's default rr_depth is 5).
RR_DEPTH = 5


@ti.func
def _medium_point(p, cone_width, cone_spread):
    return Surface(p=p, n_geo=vec3(0.0), n_shading=vec3(0.0), uv=ti.math.vec2(0.0), uv1=ti.math.vec2(0.0),
                   tangent=ti.math.vec4(0.0), material=0, prim=-1, front_face=1, eps=MEDIUM_POINT,
                   cone_width=cone_width, cone_spread=cone_spread)


@ti.func
def _medium_beyond(ctx, s, wo, wi, current):
    """The medium a ray from surface s towards wi travels in: `current` unless it crosses the
    surface; crossing inwards (from the side the outward normal faces) enters the material's
    medium, crossing outwards its outside medium (the scene's unless the material names one)."""
    medium = current
    crosses = s.eps >= 0.0 and wi.dot(s.n_geo) * wo.dot(s.n_geo) < 0.0
    if ti.static(ctx.features.has_thin):
        row = ctx.bsdf.materials.table[s.material]
        if row.thin == 1 and row.medium == NO_MEDIUM:
            # A thin wall has no inside: the light stays in the medium it was in, unless the wall
            # bounds a medium of its own (Mitsuba's thindielectric with an interior).
            crosses = False
    if crosses:
        crossed = ctx.bsdf.materials.table[s.material]
        medium = ctx.media.outside() if crossed.outside_medium == SCENE_MEDIUM else crossed.outside_medium
        if wo.dot(s.n_geo) > 0.0:
            medium = crossed.medium
    return medium


def _has_thin_walls(ctx) -> bool:
    """Whether thin dielectrics are compiled in (Python, for ti.static)."""
    return ctx.features.has_thin and ctx.features.has_kind("dielectric")


@ti.func
def _smooth_thin_wall(kind, thin, roughness_or_alpha):
    """A smooth thin dielectric: light passes it straight through, as Mitsuba's thindielectric."""
    return thin == 1 and kind == KIND_IDS["dielectric"] and roughness_or_alpha == 0.0


@ti.func
def _tint(ctx, colour, spectral, lam):
    """A colour as a spectral path sees it: its upsampled spectrum at the path's wavelength (the
    same in every channel), or the colour itself on an RGB path."""
    out = colour
    if ti.static(ctx.features.has_dispersion):
        if spectral:
            out = vec3(rgb_to_spectrum(colour, lam))
    return out


@ti.data_oriented
class PathTracerBase:
    light_sampling = True
    mis = True
    uses_lights = True
    display_tonemapper = None
    writes_aovs = True
    denoisable = True

    @ti.func
    def li(self, ctx, ray_in, state, max_depth, features_only):
        """(radiance, stats, AOV albedo, AOV normal) of a camera ray. `features_only` (a run-time
        flag of kernels that keep AOVs; False elsewhere): the path ends once its AOVs are known,
        at the first non-delta vertex, with the same decisions up to there as a whole path takes
        (its light samples come later), so these AOVs share the colour samples' distribution at
        a fraction of their cost (renderer/film/aovs.py: feature samples)."""
        radiance = vec3(0.0)
        throughput = vec3(1.0)
        ray = ray_in
        stats = vec3(0.0)
        prev_p = ray.o
        prev_n = vec3(0.0)
        prev_pdf = 0.0
        prev_delta = 1  # the camera: what it sees directly is not light-sampled
        s = _medium_point(ray.o, ray.cone_width, ray.cone_spread)  # the vertex rays leave from
        shadow_s = s  # where the pending shadow ray continues from (past null surfaces)
        next_dir = ray.d
        shadow_pending = False
        shadow_target = vec3(0.0)
        shadow_n = vec3(0.0)
        shadow_value = vec3(0.0)
        medium = NO_MEDIUM
        shadow_medium = NO_MEDIUM
        if ti.static(ctx.features.has_media):
            medium = ctx.media.outside()
        first_distance = INF  # along the camera ray (analytic fog)
        spectral = False  # the path carries one wavelength from its first dispersive surface on
        lam = 0.0
        ending = False  # the path is over once its pending shadow ray is traced
        depth = 0  # path vertices so far: each takes its own sampler dimensions
        # Bounces as max_depth and roulette count them (Mitsuba's and pbrt's depth): scattering at a
        # surface or in a medium, never the crossing of an invisible (null) boundary, nor (Mitsuba's
        # thindielectric marks it null) the straight passage through a smooth thin wall.
        bounces = 0
        at_null = False
        through_thin = False
        # Denoising AOVs (renderer/film/aovs.py): the first non-delta vertex's albedo, scaled by the
        # delta bounces before it, and its shading normal; a delta vertex is a stand-in until then.
        aov_albedo = vec3(0.0)
        aov_normal = vec3(0.0)
        aov_open = True
        aov_weight = vec3(1.0)  # the delta bounces' RGB weights (no roulette, spectral or media factors)
        for _ in range(2 * MAX_VERTICES):
            t_max = INF
            if depth > 0:
                origin = s
                if shadow_pending:
                    origin = shadow_s
                ray, t_max = ctx.geometry.next_segment(origin, next_dir, shadow_target, shadow_n, shadow_pending)
            hit = Hit(hit=0, t=t_max, work=0, tests=0, inside=0, prim=-1, bary=ti.math.vec2(0.0))
            if t_max > 0.0:
                # Shadow rays stop at the first hit they find, unless a null surface or a thin wall
                # could be that hit: passing through it needs the nearest one.
                any_hit = shadow_pending
                if ti.static(ctx.features.has_kind("null") or _has_thin_walls(ctx)):
                    any_hit = False
                hit = ctx.geometry.trace(ray, t_max, any_hit)
                stats += vec3(hit.work, hit.tests, 1.0)
            # Free flight through the path's medium (shadow rays carry its transmittance instead):
            # sampled before the surface, which a scattering event makes unneeded.
            dim = dims.BOUNCE_BASE + dims.PER_BOUNCE * depth
            scattered = False
            scatter_t = 0.0
            if ti.static(ctx.features.has_media):
                if not shadow_pending and medium != NO_MEDIUM:
                    rec = ctx.media.table[medium]
                    ms = homogeneous.sample_distance(rec.sigma_a, rec.sigma_s, hit.t if hit.hit == 1 else INF,
                                                     ctx.sampler.get1d(state, dim + dims.MEDIUM_CHANNEL),
                                                     ctx.sampler.get1d(state, dim + dims.MEDIUM_DISTANCE))
                    if ti.static(ctx.features.has_grid_media):
                        if ctx.media.grids.holds(medium):  # (its homogeneous row is empty: ms passed through)
                            ms = ctx.media.grids.free_flight(medium, ray, hit.t if hit.hit == 1 else INF, throughput,
                                                             grid.tracking_key(state, dim + dims.MEDIUM_DISTANCE, 0))
                    throughput *= _tint(ctx, ms.weight, spectral, lam)
                    scattered = ms.scattered == 1
                    scatter_t = ms.t
            hs = s
            if hit.hit == 1 and not scattered and (not shadow_pending
                                                   or ti.static(ctx.features.has_kind("null") or _has_thin_walls(ctx))):
                hs = ctx.geometry.surface(ray, hit)

            # --- a shadow ray -----------------------------------------------------------------------
            if shadow_pending:
                if ti.static(ctx.features.has_media):
                    if shadow_medium != NO_MEDIUM:
                        rec = ctx.media.table[shadow_medium]
                        shadow_value *= _tint(ctx, homogeneous.transmittance(rec.sigma_a + rec.sigma_s,
                                                                             ti.max(ti.min(hit.t, t_max), 0.0)),
                                              spectral, lam)
                        if ti.static(ctx.features.has_grid_media):
                            if ctx.media.grids.holds(shadow_medium):
                                # The pieces of one shadow ray share a dimension: salted by where each starts.
                                key = grid.tracking_key(state, dim + dims.MEDIUM_CHANNEL, grid.point_salt(ray.o))
                                tr = ctx.media.grids.transmittance(shadow_medium, ray, ti.max(ti.min(hit.t, t_max), 0.0),
                                                                   key)
                                shadow_value *= _tint(ctx, tr, spectral, lam)
                passes = False
                if hit.hit == 1:
                    if ti.static(ctx.features.has_kind("null")):
                        if ctx.bsdf.materials.table[hs.material].kind == NULL_KIND:
                            passes = True  # on through the invisible boundary, into its other side
                            if ti.static(ctx.features.has_media):
                                shadow_medium = _medium_beyond(ctx, hs, -ray.d, ray.d, shadow_medium)
                            shadow_s = hs
                    if ti.static(_has_thin_walls(ctx)):
                        row = ctx.bsdf.materials.table[hs.material]
                        if _smooth_thin_wall(row.kind, row.thin, row.roughness):
                            # Straight through a smooth thin wall, with its transmittance (Mitsuba's
                            # thindielectric passes shadow rays so, as null surfaces pass them).
                            passes = True
                            cos_i = ti.abs(ray.d.dot(hs.n_shading))
                            shadow_value *= _tint(ctx, row.base_color * (1.0 - lobes.thin_reflectance(cos_i, row.ior)),
                                                  spectral, lam)
                            if ti.static(ctx.features.has_media):
                                shadow_medium = _medium_beyond(ctx, hs, -ray.d, ray.d, shadow_medium)
                            shadow_s = hs
                else:
                    radiance += shadow_value
                if not passes:
                    shadow_pending = False
                    if ending:
                        break
                continue

            # --- the next path vertex: in the medium, on a surface, or nowhere ------------------------
            if depth == 0:
                first_distance = hit.t if hit.hit == 1 else INF
            if ti.static(ctx.features.has_media):
                if scattered:
                    rec = ctx.media.table[medium]
                    p = ray.o + scatter_t * ray.d
                    wo = -ray.d
                    if max_depth >= 0 and bounces + 1 >= max_depth:
                        break
                    s = _medium_point(p, ray.cone_width + ray.cone_spread * scatter_t, ray.cone_spread)
                    if ti.static(ctx.writes_aovs):
                        if aov_open:  # a scattering medium is a non-delta vertex: its single-scattering albedo
                            aov_albedo = aov_weight * rec.sigma_s / ti.max(rec.sigma_a + rec.sigma_s, 1e-30)
                            aov_normal = vec3(0.0)
                            aov_open = False
                        if features_only:
                            break
                    if ti.static(self.light_sampling):
                        ls = ctx.lights.sample(ctx, p, vec3(0.0), ctx.sampler.get1d(state, dim + dims.LIGHT_SELECT),
                                               ctx.sampler.get2d(state, dim + dims.LIGHT_POINT))
                        if ls.pdf > 0.0 and ls.radiance.max() > 0.0:
                            f = phase.hg_phase(rec.g, wo, ls.wi)
                            weight = 1.0
                            if ti.static(self.mis):
                                weight = light_weight(ctx.lights, ls, f)
                            shadow_pending = True
                            shadow_s = s
                            shadow_medium = medium
                            shadow_target = ls.p
                            shadow_n = ls.n
                            shadow_value = throughput * _tint(ctx, ls.radiance, spectral, lam) * (f * weight / ls.pdf)
                    wi, pdf = phase.hg_sample(rec.g, wo, ctx.sampler.get2d(state, dim + dims.BSDF_DIRECTION))
                    prev_p = p
                    prev_n = vec3(0.0)
                    prev_pdf = pdf
                    prev_delta = 0
                    next_dir = wi
            if not scattered:
                if hit.hit == 0:
                    weight = 1.0
                    if ti.static(self.light_sampling):
                        weight = environment_weight(ctx.lights, self.mis, prev_delta, prev_pdf, ray.d)
                    background = _tint(ctx, ctx.environment.radiance(ray.d), spectral, lam)
                    radiance += throughput * weight * background
                    if ti.static(ctx.writes_aovs):
                        if aov_open:
                            aov_albedo = aov_weight * ti.math.clamp(background, 0.0, 1.0)
                            aov_normal = vec3(0.0)
                    break
                s = hs
                wo = -ray.d
                mat, n = ctx.bsdf.shade(s, wo)
                if ti.static(ctx.features.has_dispersion):
                    rec = ctx.bsdf.materials.table[s.material]
                    if rec.dispersion != dispersion.NONE:
                        if not spectral:
                            spectral = True
                            lam = sample_visible_wavelength(ctx.sampler.get1d(state, dims.WAVELENGTH))
                            throughput = (spectral_rgb_weights(lam) / visible_wavelength_pdf(lam)
                                          * rgb_to_spectrum(throughput, lam))
                        mat.ior = dispersion.ior_at(rec, lam)
                if ti.static(ctx.writes_aovs):  # (compiled only where kept: no change to other kernels' code)
                    if aov_open:
                        aov_albedo = aov_weight * ctx.bsdf.albedo(mat)
                        aov_normal = n
                        aov_open = not ctx.bsdf.has_smooth_part(mat)
                    if features_only and not aov_open:
                        break
                if ti.static(ctx.features.has_emission):
                    if (s.front_face == 1 or mat.two_sided_emission == 1) and mat.emission.max() > 0.0:
                        weight = 1.0
                        if ti.static(self.light_sampling):
                            weight = emission_weight(ctx.lights, self.mis, prev_delta, prev_pdf, prev_p, prev_n, s)
                        radiance += throughput * weight * _tint(ctx, mat.emission, spectral, lam)
                if ti.static(ctx.features.has_kind("null")):
                    at_null = mat.kind == NULL_KIND
                thin_wall = False  # a smooth thin wall: passing it is no bounce, reflecting off it is
                if ti.static(_has_thin_walls(ctx)):
                    thin_wall = _smooth_thin_wall(mat.kind, mat.thin, mat.alpha)
                # Mitsuba's convention: max_depth counts path vertices, 1 = emitters seen directly.
                if max_depth >= 0 and bounces + 1 >= max_depth and not at_null and not thin_wall:
                    break
                if ti.static(self.light_sampling):
                    if ctx.bsdf.has_smooth_part(mat):
                        found, ls, f, scale = sample_direct(ctx, self.mis, mat, n, s, wo,
                                                            ctx.sampler.get1d(state, dim + dims.LIGHT_SELECT),
                                                            ctx.sampler.get2d(state, dim + dims.LIGHT_POINT))
                        if found:
                            # An environment sample's point lies far away: area lights and the
                            # environment share the shadow ray.
                            shadow_pending = True
                            shadow_s = s
                            if ti.static(ctx.features.has_media):
                                shadow_medium = _medium_beyond(ctx, s, wo, ls.wi, medium)
                            shadow_target = ls.p
                            shadow_n = ls.n
                            shadow_value = (throughput * _tint(ctx, f, spectral, lam)
                                            * _tint(ctx, ls.radiance, spectral, lam) * scale)
                bs = ctx.bsdf.sample_at(mat, n, s.n_geo, wo, ctx.sampler.get1d(state, dim + dims.BSDF_LOBE),
                                        ctx.sampler.get2d(state, dim + dims.BSDF_DIRECTION))
                if bs.valid == 0:
                    ending = True
                else:
                    throughput *= _tint(ctx, bs.weight, spectral, lam)
                    if ti.static(ctx.writes_aovs):
                        if aov_open:
                            aov_weight *= bs.weight
                    if ti.static(_has_thin_walls(ctx)):
                        if thin_wall:
                            through_thin = bs.wi.dot(s.n_geo) * wo.dot(s.n_geo) < 0.0
                            if not through_thin and max_depth >= 0 and bounces + 1 >= max_depth:
                                ending = True  # a reflection beyond the last bounce
                    if not at_null and not through_thin:
                        # An invisible boundary (or a thin wall's straight passage, which shadow rays
                        # take too) changes nothing about how the light at the end of this ray was
                        # sampled: MIS keeps the vertex before it.
                        prev_p = s.p
                        prev_n = n
                        prev_pdf = bs.pdf
                        prev_delta = bs.delta
                    next_dir = bs.wi
                    if ti.static(ctx.features.has_media):
                        medium = _medium_beyond(ctx, s, wo, bs.wi, medium)
            if not ending and bounces >= RR_DEPTH:
                q = ti.min(throughput.max(), 0.95)
                if ctx.sampler.get1d(state, dim + dims.ROULETTE) >= q:
                    ending = True
                else:
                    throughput /= q
            if ending and not shadow_pending:
                break
            if scattered or not (at_null or through_thin):
                bounces += 1
            at_null = False
            through_thin = False
            depth += 1
        if ti.static(ctx.features.analytic_fog):
            fog = ctx.media.fog[None]
            radiance = homogeneous.exponential_fog(radiance, fog.xyz, fog.w, first_distance)
        return radiance, stats, aov_albedo, aov_normal

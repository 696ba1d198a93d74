"""Where light leaves the emitters: starting rays for light paths (photons).

`Lights` answers "which light reaches this point?" (directions and densities at a reference point,
for direct lighting). Photon mapping asks the reverse: "where does light start, going where, with
how much power?". This module answers that for the same emitters, without changing `Lights`:

  sample(ctx, u_select, u_point, u_dir, u_mix) -> EmittedPhoton
      o, d       the ray's origin and direction (world)
      beta       the power it carries, Le |cos| / (p(choice) p(point) p(direction)), so that the
                 sum of `beta` over N photons divided by N estimates the scene's emitted power
      surface    the emitter's surface record (for `geometry.spawn`), or none (environment)
      from_env   1 for environment photons, whose origin is already off every surface

Emissive primitives (triangles, quads, discs, spheres of meshes; spheres of SDF scenes) are chosen
in proportion to their power (luminance x area x pi, as `emitter_table` computes it), a point is
drawn uniformly over the chosen one's area, and the direction is cosine-weighted about its normal
(a Lambertian emitter's radiance is the same in every direction of its front hemisphere). The
points come from the geometry's own `sample_emitter(prim, ref, u)` seen from an anchor point where
that routine samples by area: flat shapes sample their area uniformly from any point off their
plane (the anchor sits one bounding-box diagonal in front of the shape), and a sphere seen from its
centre is sampled uniformly over its whole surface (`emitter_shapes.sphere_sample`'s inside case).
So no shape's geometry is duplicated here, and SDF and mesh scenes take the same path.

The environment (map, sky or constant colour) emits from a disc perpendicular to the direction
the light comes from, of the radius of the scene's bounding sphere, placed outside it (pbrt's
method): the direction comes from the environment's own importance sampler (a map) or uniformly
from the sphere, the point uniformly from the disc. Mesh scenes take the bounding sphere of their
geometry. SDF scenes have no finite bounds (planes, infinite repetitions), so their sphere is set
per photon pass by the caller (SPPM uses the bounds of the camera and of the pass's visible points
that are not far beyond their typical distance): environment light that reaches the image only
through surfaces outside that sphere is missed (a bias SPPM accepts on SDF scenes).

Aiming. A caller may name a target region (a sphere; SPPM: the camera and the visible points of
the pass). A share TARGET_SHARE of the photons is then aimed at it: from an emitter outside it,
uniformly in the cone it subtends; from the environment, through the target's disc instead of the
scene's. The other photons leave as above, and every photon's power divides by the density of the
two-way mixture, so the estimate stays unbiased and what lies outside the target still gets light.

Whether a photon comes from the environment or from a primitive is decided by the two powers (the
environment's: its integrated luminance times the disc's area), so the photon budget follows
where the light is.
"""
import math

import numpy as np
import taichi as ti

from renderer.geometry.interface import Surface
from renderer.lights.lights import choose_environment, emitted_radiance, environment_direction, environment_emits
from renderer.spectral.luminance import LUMINANCE_WEIGHTS
from renderer.sampling.cdf import cdf_interval
from renderer.sampling.warps import PI, concentric_disk, cosine_hemisphere, orthonormal_basis, to_world
from renderer.runtime.upload import upload_fields

vec3 = ti.math.vec3

EmittedPhoton = ti.types.struct(o=vec3, d=vec3, beta=vec3, surface=Surface, from_env=ti.i32, valid=ti.i32)

LUMINANCE = np.array(LUMINANCE_WEIGHTS)
# The share of photons aimed at the target region (the part of the scene the camera sees), the rest
# leaving as they would without a target (cosine-weighted, or through the whole scene's disc). Each
# photon's power divides by the mixture of the two densities: aiming changes the noise, never the
# expected value, and the rest of the scene still gets light. A distant sun (a small sphere tens of
# metres away) otherwise sends nearly all of its photons past the scene.
TARGET_SHARE = 0.75
# Origin offset of a photon leaving an emitter, as a fraction of the emitter's size (sqrt(area)),
# handed to `geometry.spawn` as the surface's epsilon: SDF spawns start 2.5 epsilons off the
# surface (mesh spawns ignore it and offset by ulps). 1e-3 of the emitter is far below anything
# visible, and above the sphere tracer's default hit threshold (1e-4 m) for emitters of 10 cm and
# more; MIN_EMIT_EPS keeps smaller ones clear of it too.
EMIT_EPS_FRACTION = 1e-3
MIN_EMIT_EPS = 2e-4


def environment_integral(env_spec, env_sampler=None) -> float:
    """An estimate of the integral of the environment's luminance over all directions (its power
    through a unit area facing each direction), for choosing between environment and primitive
    photons. Only the photon budget depends on it, never the image's expected value."""
    if not environment_emits(env_spec):
        return 0.0
    if env_spec.kind == "map":
        # The sampler's conservative total: sum over texels of (max luminance) x (solid angle).
        return float(env_sampler.ratio_bound) * env_spec.intensity if env_sampler is not None else 4 * math.pi
    if env_spec.kind == "constant":
        return 4 * math.pi * float(LUMINANCE @ np.asarray(env_spec.color)) * env_spec.intensity
    # sky: the upper hemisphere blends horizon to zenith, the lower one is mostly the ground
    upper = 0.5 * float(LUMINANCE @ (np.asarray(env_spec.zenith) + np.asarray(env_spec.horizon)))
    lower = float(LUMINANCE @ np.asarray(env_spec.ground))
    return 2 * math.pi * (upper + lower) * env_spec.intensity


@ti.data_oriented
class Emission:
    """Photon emission from a scene's emitters (see the module docstring)."""

    def __init__(self, geometry, lights, env_spec, scene_bounds=None):
        """lights: the scene's `Lights` (its emitter table and environment sampler are shared);
        scene_bounds: (lo, hi) of a finite scene, or None when the caller sets the bounding sphere
        per pass (`set_bounds_kernel`)."""
        self.geometry = geometry
        self.lights = lights  # its environment sampling serves environment photons
        table = lights.emitters
        prims = np.asarray(table["prim"]).astype(np.int32)
        area = np.asarray(table["area"], np.float64)
        lo, hi = np.asarray(table["lo"], np.float64), np.asarray(table["hi"], np.float64)
        axis = np.asarray(table["axis"], np.float64)
        two_sided = np.asarray(table.get("two_sided", np.zeros(len(table["prim"]), bool)), bool)
        # spheres emit all around (a flat shape emitting from both faces is still aimed at from one)
        all_round = (np.asarray(table["theta_o"], np.float64) > 0.5 * math.pi) & ~two_sided
        power = np.asarray(table["power"], np.float64)
        self.count = len(prims)
        self.has_two_sided = bool(two_sided.any())  # (the face choice compiled in only then)
        self.has_area = self.count > 0 and float(power.sum()) > 0.0
        self.has_env = lights.has_env
        self.area_power = float(power.sum()) if self.has_area else 0.0
        self.env_integral = environment_integral(env_spec, getattr(lights, "env_sampler", None))
        n = max(1, self.count)
        self.prim = ti.field(ti.i32, shape=n)
        self.area = ti.field(ti.f32, shape=n)
        self.eps = ti.field(ti.f32, shape=n)
        self.two_sided = ti.field(ti.i32, shape=n)
        self.anchor = ti.Vector.field(3, ti.f32, shape=n)
        self.cdf = ti.field(ti.f32, shape=n + 1)
        # [centre.xyz, radius] of the scene's bounding sphere; [area power, env integral]
        self.sphere = ti.Vector.field(4, ti.f32, shape=())
        # [centre.xyz, radius] of the region photons are aimed at (radius 0: none), set per pass
        self.target = ti.Vector.field(4, ti.f32, shape=())
        self.powers = ti.field(ti.f32, shape=2)
        if self.has_area:
            centre = 0.5 * (lo + hi)
            diagonal = np.linalg.norm(hi - lo, axis=1, keepdims=True)
            # Flat shapes: one diagonal (plus a margin for degenerate boxes) in front of the plane;
            # spheres: their centre.
            anchor = np.where(all_round[:, None], centre, centre + axis * (diagonal + 1e-3))
            upload_fields([(self.prim, prims), (self.area, area), (self.anchor, anchor),
                           (self.two_sided, two_sided.astype(np.int32)),
                           (self.eps, np.maximum(MIN_EMIT_EPS, EMIT_EPS_FRACTION * np.sqrt(area)))])
        self._upload_powers(power)
        self.bounds_per_pass = scene_bounds is None
        if scene_bounds is not None:
            self.set_bounds(*scene_bounds)

    def _upload_powers(self, power) -> None:
        if self.has_area:
            cdf = np.concatenate([[0.0], np.cumsum(power)]) / power.sum()
            cdf[-1] = 1.0
            upload_fields([(self.cdf, cdf)])
        upload_fields([(self.powers, np.array([self.area_power, self.env_integral], np.float32))])

    def refit(self, env_spec) -> bool:
        """The emitters' powers and the environment's integral taken again from the Lights (after
        Lights.refit, or an environment edit of the same kind) into the same fields: no compile.
        False where which emitters or sides emit changed: build it anew then."""
        table = self.lights.emitters
        power = np.asarray(table["power"], np.float64)
        if len(power) != self.count or (self.count > 0 and float(power.sum()) > 0.0) != self.has_area \
                or self.lights.has_env != self.has_env:
            return False
        self.area_power = float(power.sum()) if self.has_area else 0.0
        self.env_integral = environment_integral(env_spec, getattr(self.lights, "env_sampler", None))
        self._upload_powers(power)
        return True

    @property
    def emits(self) -> bool:
        return self.has_area or self.has_env

    def set_bounds(self, lo, hi) -> None:
        """The scene's bounding sphere from an axis-aligned box (numpy)."""
        lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
        centre = 0.5 * (lo + hi)
        radius = 0.5 * float(np.linalg.norm(hi - lo))
        self.sphere[None] = ti.math.vec4(*centre, max(radius, 1e-6))

    @ti.func
    def set_bounds_func(self, lo, hi):
        """Device-side set_bounds (SDF scenes: per pass, from the caller's bounds)."""
        self.sphere[None] = ti.math.vec4(0.5 * (lo + hi), ti.max(0.5 * (hi - lo).norm(), 1e-6))

    @ti.func
    def set_target_func(self, lo, hi):
        """The region most photons are aimed at (SPPM: the camera and its typical visible points)."""
        self.target[None] = ti.math.vec4(0.5 * (lo + hi), ti.max(0.5 * (hi - lo).norm(), 1e-6))

    @ti.func
    def env_probability(self):
        """The share of photons leaving from the environment (by power)."""
        p = 0.0
        if ti.static(self.has_env):
            p = 1.0
            if ti.static(self.has_area):
                r = self.sphere[None].w
                env_power = self.powers[1] * PI * r * r
                total = env_power + self.powers[0]
                p = env_power / total if total > 0.0 else 0.5
        return p

    @ti.func
    def _select(self, u):
        """The emitter whose CDF interval holds u, and its probability. (Not the power selector's
        alias table: that maps u to other emitters, so the photons, and SPPM's images, would
        change.)"""
        e = cdf_interval(self.cdf, 0, self.count, u)
        return e, self.cdf[e + 1] - self.cdf[e]

    @ti.func
    def _line_enters(self, sphere, o, d):
        """Where the line o + t d (d unit) enters `sphere` (t, possibly negative), and whether it
        meets it at all."""
        oc = o - sphere.xyz
        b = oc.dot(d)
        c = oc.dot(oc) - sphere.w * sphere.w
        disc = b * b - c
        return -b - ti.sqrt(ti.max(disc, 0.0)), disc >= 0.0

    @ti.func
    def sample(self, ctx, u_select, u_point, u_dir, u_mix):
        """u_mix chooses between aiming at the target sphere (share TARGET_SHARE) and the plain
        strategy (cosine-weighted from emitters, the scene's disc for the environment); the
        photon's power divides by the mixture's density, so nothing is left out."""
        none = Surface(p=vec3(0.0), n_geo=vec3(0.0, 1.0, 0.0), n_shading=vec3(0.0, 1.0, 0.0), uv=ti.math.vec2(0.0),
                       uv1=ti.math.vec2(0.0), tangent=ti.math.vec4(0.0), material=0, prim=-1, front_face=1, eps=0.0,
                       cone_width=0.0, cone_spread=0.0)
        result = EmittedPhoton(o=vec3(0.0), d=vec3(0.0, 1.0, 0.0), beta=vec3(0.0), surface=none, from_env=0, valid=0)
        p_env = self.env_probability()
        target = self.target[None]
        use_env, u = choose_environment(self.has_env, p_env, u_select)
        if use_env:
            if ti.static(self.has_env):
                w, pdf_dir, radiance = environment_direction(self.lights, u_point)
                sphere = self.sphere[None]
                chosen = sphere
                share = TARGET_SHARE if target.w > 0.0 else 0.0
                if u_mix < share:
                    chosen = target
                t, b = orthonormal_basis(w)
                disc = concentric_disk(u_dir) * chosen.w
                o = chosen.xyz + disc.x * t + disc.y * b  # a point of the line, in the disc's plane
                t_scene, in_scene = self._line_enters(sphere, o, -w)
                t_target, in_target = self._line_enters(target, o, -w)
                # The mixture's area density (perpendicular to w) of drawing this line: each disc
                # gives 1 / (pi r^2) to the lines that meet its sphere.
                density = 0.0
                if in_target and share > 0.0:  # (no target: radius 0)
                    density += share / (PI * target.w * target.w)
                if in_scene:
                    density += (1.0 - share) / (PI * sphere.w * sphere.w)
                # Start where the line first enters either sphere: nothing lies before that, and a
                # sphere tracer's range counts from there.
                start = t_target if in_target else t_scene
                if in_scene and in_target:
                    start = ti.min(t_scene, t_target)
                if pdf_dir > 0.0 and radiance.max() > 0.0 and density > 0.0:
                    # flux through the disc: L dA dw / (p(w) p(point) p(env))
                    beta = radiance / (pdf_dir * density * p_env)
                    result = EmittedPhoton(o=o - start * w, d=-w, beta=beta, surface=none, from_env=1, valid=1)
        else:
            if ti.static(self.has_area):
                e, pmf = self._select(ti.min(u, 0.99999994))
                g = self.prim[e]
                pt = self.geometry.sample_emitter(g, self.anchor[e], u_point)
                if pt.pdf > 0.0 and pmf > 0.0:
                    # Aim at the target only from outside it (from inside, the cone is everything).
                    to_c = target.xyz - pt.p
                    d2 = to_c.dot(to_c)
                    r2 = target.w * target.w
                    share = TARGET_SHARE if (target.w > 0.0 and d2 > r2 * 1.0001) else 0.0
                    axis = to_c / ti.sqrt(ti.max(d2, 1e-30))
                    sin2_max = ti.min(r2 / ti.max(d2, 1e-30), 1.0)
                    cos_max = ti.sqrt(ti.max(0.0, 1.0 - sin2_max))
                    one_minus_cos_max = sin2_max / (1.0 + cos_max)  # accurate for small cones
                    d = vec3(0.0, 1.0, 0.0)
                    # A two-sided emitter's cosine-weighted directions go to either face, half each.
                    sides = 1.0
                    if ti.static(self.has_two_sided):
                        sides = 2.0 if self.two_sided[e] == 1 else 1.0
                    if u_mix < share:
                        # uniform in the cone the target subtends
                        one_minus_cos = u_dir.x * one_minus_cos_max
                        cos_t = 1.0 - one_minus_cos
                        sin_t = ti.sqrt(ti.max(0.0, one_minus_cos * (2.0 - one_minus_cos)))
                        phi = 2.0 * PI * u_dir.y
                        ta, tb = orthonormal_basis(axis)
                        d = ti.cos(phi) * sin_t * ta + ti.sin(phi) * sin_t * tb + cos_t * axis
                    else:
                        face = pt.n
                        if sides > 1.0 and (u_mix - share) < 0.5 * (1.0 - share):
                            face = -pt.n
                        t, b = orthonormal_basis(face)
                        d = to_world(cosine_hemisphere(u_dir), t, b, face)
                    cos_n = d.dot(pt.n)
                    if sides > 1.0:
                        cos_n = ti.abs(cos_n)
                        pt.n = pt.n if d.dot(pt.n) > 0.0 else -pt.n  # the face the photon leaves
                    in_cone = 1.0 - d.dot(axis) <= one_minus_cos_max
                    pdf_dir = (1.0 - share) * ti.max(cos_n, 0.0) / PI
                    if ti.static(self.has_two_sided):
                        pdf_dir /= sides
                    if share > 0.0 and in_cone:
                        pdf_dir += share / (2.0 * PI * one_minus_cos_max)
                    if cos_n > 0.0 and pdf_dir > 0.0:  # from the front face only, unless two-sided
                        radiance = emitted_radiance(ctx, self.geometry, g, pt.p, pt.n, pt.uv, d)
                        # Le cos / (pmf (1 - p_env) (1 / area) pdf_dir)
                        beta = radiance * (cos_n * self.area[e] / (pmf * (1.0 - p_env) * pdf_dir))
                        s = Surface(p=pt.p, n_geo=pt.n, n_shading=pt.n, uv=pt.uv, uv1=pt.uv,
                                    tangent=ti.math.vec4(0.0), material=self.geometry.material_of(g), prim=g,
                                    front_face=1, eps=self.eps[e], cone_width=0.0, cone_spread=0.0)
                        result = EmittedPhoton(o=pt.p, d=d, beta=beta, surface=s, from_env=0,
                                               valid=1 if radiance.max() > 0.0 else 0)
        return result

    # --- host helpers (tests) -------------------------------------------------------------------------

    def total_power(self) -> float:
        """The luminance power the photons carry on average (area emitters plus the environment
        through the current bounding sphere's disc)."""
        r = float(self.sphere[None][3])
        return self.area_power + (self.env_integral * math.pi * r * r if self.has_env else 0.0)

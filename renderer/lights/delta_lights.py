"""Lights without a surface: point, spot and directional (Mitsuba 3's and pbrt-v4's), projector
(Mitsuba 3's).

Each is a delta distribution, in position (point, spot, projector) or in direction (directional): no ray can
hit one, and a light sample finds it with a density that is a Dirac delta, so its contribution
is taken by light sampling alone, with no MIS weight (pbrt-v4's `LightType::DeltaPosition` and
`DeltaDirection`). A path tracer that samples BSDFs only (`path`) never sees them.

  point        intensity I (W/sr per channel): radiance I / r^2 arrives from the light's position
  spot         a point light times Mitsuba 3's falloff about its axis: 1 within beam_width of the
               axis, (cutoff - theta) / (cutoff - beam_width) between, 0 beyond cutoff_angle
  directional  irradiance E (W/m^2) travelling along its direction, from outside the scene
  projector    a pinhole projecting an image E(uv): pi E(uv) r / z^3 at distance r and depth z
A spot's texture multiplies its intensity over the cone, and a projector's image is read, at the
uv renderer/lights/light_projection.py defines; both images live in the lights' own texture table,
compiled in only where a scene has such an image (`features.has_light_textures`).

`DeltaLights.sample(features, e, ref)` gives light e's direction, distance (INF: directional),
the radiance-like value that multiplies f / pmf (I falloff / r^2, E, or the projector's) and the
light's position.
Only the kinds `features.light_kinds` names are compiled.

Choosing among them (`DeltaLights.choose`): by default, where a scene has at most LOCAL_MAX of
them, in proportion to what each would bring to the shading point unshadowed (the luminance of
its value, times |cos| to the point's normal where it has one): every light is evaluated, one
pass, one uniform number (a weighted reservoir of one). Light that is concentrated (spots,
projectors) is then found where it lands, rather than in proportion to a power that a point light
spread over the whole sphere dominates. With more lights, in proportion to their power (luminance)
(`make_delta_selector`); uniformly where the scene asks for the uniform light selector. The caller
divides by the probability. Power: point 4 pi I; spot 2 pi I (1 - (sin c - sin b) / (c - b)) (the falloff
integrated over the sphere; 2 pi I (1 - cos c) when b = c); directional pi R^2 E with R the scene's
bounding radius (the power that crosses the scene); a projector pi E over its image at distance 1;
images scale these by their mean luminance. These steer the noise, never the expected value.
"""

import math

import numpy as np
import taichi as ti

from renderer.geometry.interface import INF
from renderer.lights.light_projection import (image_aspect, light_frame, mean_luminance, projection_scale,
                                              projector_power)
from renderer.lights.light_select import PowerSelector, SingleEmitterSelector, UniformSelector
from renderer.lights.light_tree_build import EmitterBounds
from renderer.materials.texture_sampler import TextureTable
from renderer.runtime.upload import upload_fields
from renderer.sampling.warps import PI
from renderer.scene.limits import MemoryBudget, MemoryLedger
from renderer.scene.texture_images import texture_image
from renderer.scene.textures import WRAP_CODES, pack_atlas
from renderer.spectral.luminance import LUMINANCE_WEIGHTS

vec3 = ti.math.vec3

POINT, SPOT, DIRECTIONAL, PROJECTOR = 0, 1, 2, 3
KIND_CODES = {"point": POINT, "spot": SPOT, "directional": DIRECTIONAL, "projector": PROJECTOR}
NO_IMAGE = -1
LOCAL_MAX = 16  # "auto" chooses by each light's contribution at the point up to this many lights


# --- host side (numpy): the profile and the powers, shared with the tests -------------------------

def spot_falloff(theta, cutoff_deg: float, beam_deg: float):
    """Mitsuba 3's spot profile at angles theta (radians) from the axis: 1 within the beam, linear
    in angle down to 0 at the cutoff, 0 beyond."""
    theta = np.asarray(theta, np.float64)
    cutoff, beam = math.radians(cutoff_deg), math.radians(beam_deg)
    ramp = (cutoff - theta) / (cutoff - beam) if cutoff > beam else np.zeros_like(theta)
    return np.where(theta <= beam, 1.0, np.where(theta < cutoff, ramp, 0.0))


def spot_solid_angle(cutoff_deg: float, beam_deg: float) -> float:
    """The falloff integrated over the sphere (sr): a spot's power is its intensity times this."""
    c, b = math.radians(cutoff_deg), math.radians(beam_deg)
    if c - b < 1e-9:
        return 2.0 * math.pi * (1.0 - math.cos(c))
    return 2.0 * math.pi * (1.0 - (math.sin(c) - math.sin(b)) / (c - b))


def light_power(spec, scene_radius: float, image=None) -> float:
    """A light's luminance power (W), for choosing among lights; image: its `TextureImage`, if any."""
    weights = np.array(LUMINANCE_WEIGHTS)
    if spec.kind == "directional":
        return float(weights @ np.asarray(spec.irradiance)) * math.pi * scene_radius ** 2
    if spec.kind == "projector":
        return projector_power(spec, image)
    intensity = float(weights @ np.asarray(spec.intensity))
    if spec.kind == "spot":
        return intensity * spot_solid_angle(spec.cutoff_angle, spec.beam) * (
            mean_luminance(image) if image is not None else 1.0)
    return intensity * 4.0 * math.pi


def peak_intensity(spec, power: float) -> float:
    """The most a light sends a point at distance 1 (luminance W/sr, or the same measure for a
    directional light's power crossing the scene): a point or a spot its intensity, others their
    power over pi, as a Lambertian emitter of that power would (what the choice between these lights
    and emissive surfaces weighs, renderer/lights/lights.py)."""
    if spec.kind == "point":
        return power / (4.0 * math.pi)
    if spec.kind == "spot":
        return power / spot_solid_angle(spec.cutoff_angle, spec.beam)
    return power / math.pi


def emits(spec) -> bool:
    return max(spec.irradiance if spec.kind in ("directional", "projector") else spec.intensity) > 0.0


def light_images(specs, ledger: MemoryLedger):
    """(images, their texture slots (as TextureTable takes them), each light's slot or NO_IMAGE)."""
    images, slots, slot_of = [], [], []
    for spec in specs:
        if spec.texture is None or spec.kind not in ("spot", "projector"):
            slot_of.append(NO_IMAGE)
            continue
        images.append(texture_image(spec.texture, ledger))
        wrap = WRAP_CODES[spec.texture.wrap]
        slots.append((len(images) - 1, wrap, wrap, 0, np.array(spec.texture.transform, np.float32),
                      spec.texture.nearest))
        slot_of.append(len(slots) - 1)
    return images, slots, slot_of


def make_delta_selector(kind: str, power: np.ndarray):
    """A light selector over the delta lights: uniform for the "uniform" kind, else by power
    (the light tree and its bounds are for emitters with a surface)."""
    n = len(power)
    if n == 1:
        return SingleEmitterSelector(1)
    if kind == "uniform":
        return UniformSelector(n)
    return PowerSelector(power_bounds(power))


def power_bounds(power) -> EmitterBounds:
    """Lights without a surface as the power selector takes them: their powers alone."""
    n = len(power)
    zeros = np.zeros((n, 3))
    return EmitterBounds(lo=zeros, hi=zeros, power=np.asarray(power, np.float64), axis=zeros, theta_o=np.zeros(n),
                         theta_e=np.zeros(n))


# --- device side ------------------------------------------------------------------------------

@ti.data_oriented
class DeltaLights:
    """The scene's point, spot, directional and projector lights on the device (those that emit).
    ledger: what the scene's files were charged so far (its model files'), which the lights'
    images join; None: a ledger of its own."""

    def __init__(self, specs, scene_radius: float, selector_kind: str = "auto", ledger: MemoryLedger | None = None):
        specs = [s for s in specs if emits(s)]
        self.count = len(specs)
        images, slots, slot_of = light_images(specs, ledger or MemoryLedger(MemoryBudget.from_settings()))
        image_of = [images[slots[k][0]] if k != NO_IMAGE else None for k in slot_of]
        self.power = np.array([light_power(s, scene_radius, im) for s, im in zip(specs, image_of)], np.float64)
        self.intensity = np.array([peak_intensity(s, p) for s, p in zip(specs, self.power)], np.float64)
        n = max(1, self.count)
        self.kind = ti.field(ti.i32, shape=n)
        self.position = ti.Vector.field(3, ti.f32, shape=n)
        self.direction = ti.Vector.field(3, ti.f32, shape=n)  # spot: axis; directional: travel
        self.value = ti.Vector.field(3, ti.f32, shape=n)  # intensity, or irradiance
        # spot: cos(cutoff), cos(beam), cutoff (radians), 1 / (cutoff - beam) (0: a hard edge)
        self.cone = ti.Vector.field(4, ti.f32, shape=n)
        # spot, projector: rows = the light's local axes; (k_u, k_v) of light_projection.py; image slot
        self.frame = ti.Matrix.field(3, 3, ti.f32, shape=n)
        self.projection = ti.Vector.field(2, ti.f32, shape=n)
        self.image = ti.field(ti.i32, shape=n)
        # The images' own table: only scenes whose lights have images compile its lookups.
        self.textures = None
        self.has_images = bool(slots)
        if slots:
            atlas = pack_atlas(images)
            self.textures = TextureTable(atlas, [(atlas.rects[slot[0]], *slot[1:]) for slot in slots])
        self.specs, self.image_of = specs, image_of
        if self.count:
            self._upload(np.array(slot_of, np.int32))
            self.selector = make_delta_selector(selector_kind, self.power)
        # Compiled in: whether choose() weighs every light at the shading point.
        self.local = selector_kind == "auto" and 1 < self.count <= LOCAL_MAX

    def _upload(self, slots=None) -> None:
        specs, n = self.specs, self.count
        cone = np.zeros((n, 4))
        frames = np.tile(np.eye(3), (n, 1, 1))
        projection = np.zeros((n, 2))
        for i, s in enumerate(specs):
            if s.kind == "spot":
                c, b = math.radians(s.cutoff_angle), math.radians(s.beam)
                cone[i] = (math.cos(c), math.cos(b), c, 1.0 / (c - b) if c > b else 0.0)
            if s.kind in ("spot", "projector"):
                frames[i] = light_frame(s)
                projection[i] = projection_scale(s, image_aspect(self.image_of[i]))
        direction = np.array([s.direction for s in specs], np.float64)
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        upload_fields([(self.kind, np.array([KIND_CODES[s.kind] for s in specs], np.int32)),
                       (self.position, np.array([s.position for s in specs], np.float32)),
                       (self.direction, direction.astype(np.float32)),
                       (self.value, np.array([s.irradiance if s.kind in ("directional", "projector")
                                              else s.intensity for s in specs], np.float32)),
                       (self.cone, cone.astype(np.float32)),
                       (self.frame, frames.astype(np.float32)),
                       (self.projection, projection.astype(np.float32))]
                      + ([(self.image, slots)] if slots is not None else []))

    def refit(self, specs, scene_radius: float) -> bool:
        """Take edited lights (values, places, directions, cones) in place, into the same fields:
        no kernel compiles. False, nothing changed, where the lights that emit, their kinds or
        their images differ: build them anew then."""
        specs = [s for s in specs if emits(s)]
        if [(s.kind, s.texture) for s in specs] != [(s.kind, s.texture) for s in self.specs]:
            return False
        power = np.array([light_power(s, scene_radius, im) for s, im in zip(specs, self.image_of)], np.float64)
        if self.count > 1 and not self.selector.refit(power_bounds(power)):
            return False
        self.specs, self.power = specs, power
        self.intensity = np.array([peak_intensity(s, p) for s, p in zip(specs, power)], np.float64)
        if self.count:
            self._upload()
        return True

    @ti.func
    def choose(self, features: ti.template(), ref, ref_n, u):
        """One light for the point ref (normal ref_n; zero in a medium) from a uniform u in [0, 1):
        (pmf, wi, dist, value, position) as `sample` gives them, pmf the probability of the
        choice (0 with a zero value where no light reaches ref)."""
        pmf = 0.0
        wi = vec3(0.0, 0.0, 1.0)
        dist = INF
        value = vec3(0.0)
        position = ref
        if ti.static(self.local):
            total = 0.0
            chosen = 0.0
            v = u
            for e in range(self.count):
                e_wi, e_dist, e_value, e_position = self.sample(features, e, ref)
                cos = ti.abs(ref_n.dot(e_wi)) if ref_n.norm_sqr() > 0.0 else 1.0
                w = e_value.dot(vec3(LUMINANCE_WEIGHTS)) * cos
                if w > 0.0:
                    total += w
                    p = w / total  # keep light e with probability w / total so far
                    if v < p:
                        wi, dist, value, position, chosen = e_wi, e_dist, e_value, e_position, w
                        v = v / p
                    else:
                        v = (v - p) / (1.0 - p)
            if total > 0.0:
                pmf = chosen / total
        else:
            e, pmf = self.selector.select(ref, ref_n, u)
            wi, dist, value, position = self.sample(features, e, ref)
        return pmf, wi, dist, value, position

    @ti.func
    def falloff(self, e, w):
        """Spot e's profile in the unit direction w leaving it (Mitsuba 3's falloff_curve)."""
        cone = self.cone[e]
        cos_theta = self.direction[e].dot(w)
        result = 0.0
        if cos_theta > cone[0]:
            result = 1.0
            if cos_theta < cone[1]:
                result = (cone[2] - ti.acos(ti.min(cos_theta, 1.0))) * cone[3]
        return result

    @ti.func
    def image_value(self, features: ti.template(), e, local):
        """Light e's image where the light-frame point or direction `local` (z > 0) meets it; 1
        for a light without an image."""
        value = vec3(1.0)
        if ti.static(features.has_light_textures and self.has_images):
            slot = self.image[e]
            if slot != NO_IMAGE:
                k = self.projection[e]
                uv = 0.5 + 0.5 * ti.math.vec2(k.x * local.x, k.y * local.y) / local.z
                value = self.textures.sample(slot, uv, uv).xyz
        return value

    @ti.func
    def projected(self, features: ti.template(), e, offset, dist):
        """Projector e's value at `offset` from it, distance dist: pi E(uv) r / z^3 inside its
        image, 0 outside it or behind the projector (Mitsuba's projector)."""
        local = self.frame[e] @ offset
        value = vec3(0.0)
        if local.z > 0.0:
            k = self.projection[e]
            uv = 0.5 + 0.5 * ti.math.vec2(k.x * local.x, k.y * local.y) / local.z
            if uv.x >= 0.0 and uv.x <= 1.0 and uv.y >= 0.0 and uv.y <= 1.0:
                depth3 = local.z * local.z * local.z
                value = self.value[e] * self.image_value(features, e, local) * (PI * dist / depth3)
        return value

    @ti.func
    def sample(self, features: ti.template(), e, ref):
        """(wi, dist, value, position) of light e seen from ref: the unit direction towards it, the
        distance (INF for a directional light, whose position is then meaningless), the value
        that multiplies f / pmf (I falloff / r^2, E, or a projector's), and the light's position."""
        wi = vec3(0.0, 0.0, 1.0)
        dist = INF
        value = vec3(0.0)
        position = ref
        k = self.kind[e]
        if ti.static(features.has_light("directional")):
            if k == DIRECTIONAL:
                wi = -self.direction[e]
                value = self.value[e]
        if ti.static(features.has_light("point") or features.has_light("spot") or features.has_light("projector")):
            if k != DIRECTIONAL:
                to = self.position[e] - ref
                d2 = to.norm_sqr()
                if d2 > 0.0:
                    dist = ti.sqrt(d2)
                    wi = to / dist
                    value = self.value[e] / d2
                    position = self.position[e]
                    if ti.static(features.has_light("spot")):
                        if k == SPOT:
                            value *= self.falloff(e, -wi)
                            if ti.static(features.has_light_textures):
                                local = self.frame[e] @ -wi
                                if value.max() > 0.0 and local.z > 0.0:  # inside the cone: its image there
                                    value *= self.image_value(features, e, local)
                    if ti.static(features.has_light("projector")):
                        if k == PROJECTOR:
                            value = self.projected(features, e, -to, dist)
        return wi, dist, value, position

"""Lights without a surface: point, spot and directional (Mitsuba 3's and pbrt-v4's).

Each is a delta distribution, in position (point, spot) or in direction (directional): no ray can
hit one, and a light sample finds it with a density that is a Dirac delta, so its contribution
is taken by light sampling alone, with no MIS weight (pbrt-v4's `LightType::DeltaPosition` and
`DeltaDirection`). A path tracer that samples BSDFs only (`path`) never sees them.

  point        intensity I (W/sr per channel): radiance I / r^2 arrives from the light's position
  spot         a point light times Mitsuba 3's falloff about its axis: 1 within beam_width of the
               axis, (cutoff - theta) / (cutoff - beam_width) between, 0 beyond cutoff_angle
  directional  irradiance E (W/m^2) travelling along its direction, from outside the scene

`DeltaLights.sample(features, e, ref)` gives light e's direction, distance (INF: directional),
the radiance-like value that multiplies f / pmf (I falloff / r^2, or E) and the light's position.
Only the kinds `features.light_kinds` names are compiled.

Choosing among them (`make_delta_selector`): in proportion to their power (luminance), or
uniformly where the scene asks for the uniform light selector; the caller divides by the
probability. Power: point 4 pi I; spot 2 pi I (1 - (sin c - sin b) / (c - b)) (the falloff
integrated over the sphere; 2 pi I (1 - cos c) when b = c); directional pi R^2 E with R the scene's
bounding radius (the power that crosses the scene). These steer the noise, never the expected value.
"""

import math

import numpy as np
import taichi as ti

from renderer.geometry.interface import INF
from renderer.lights.light_select import PowerSelector, SingleEmitterSelector, UniformSelector
from renderer.lights.light_tree_build import EmitterBounds
from renderer.runtime.upload import upload_fields
from renderer.spectral.luminance import LUMINANCE_WEIGHTS

vec3 = ti.math.vec3

POINT, SPOT, DIRECTIONAL = 0, 1, 2
KIND_CODES = {"point": POINT, "spot": SPOT, "directional": DIRECTIONAL}


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


def light_power(spec, scene_radius: float) -> float:
    """A light's luminance power (W), for choosing among lights."""
    weights = np.array(LUMINANCE_WEIGHTS)
    if spec.kind == "directional":
        return float(weights @ np.asarray(spec.irradiance)) * math.pi * scene_radius ** 2
    intensity = float(weights @ np.asarray(spec.intensity))
    if spec.kind == "spot":
        return intensity * spot_solid_angle(spec.cutoff_angle, spec.beam)
    return intensity * 4.0 * math.pi


def emits(spec) -> bool:
    return max(spec.irradiance if spec.kind == "directional" else spec.intensity) > 0.0


def make_delta_selector(kind: str, power: np.ndarray):
    """A light selector over the delta lights: uniform for the "uniform" kind, else by power
    (the light tree and its bounds are for emitters with a surface)."""
    n = len(power)
    if n == 1:
        return SingleEmitterSelector(1)
    if kind == "uniform":
        return UniformSelector(n)
    zeros = np.zeros((n, 3))
    return PowerSelector(EmitterBounds(lo=zeros, hi=zeros, power=np.asarray(power, np.float64), axis=zeros,
                                       theta_o=np.zeros(n), theta_e=np.zeros(n)))


# --- device side ------------------------------------------------------------------------------

@ti.data_oriented
class DeltaLights:
    """The scene's point, spot and directional lights on the device (those that emit)."""

    def __init__(self, specs, scene_radius: float, selector_kind: str = "auto"):
        specs = [s for s in specs if emits(s)]
        self.count = len(specs)
        self.power = np.array([light_power(s, scene_radius) for s in specs], np.float64)
        n = max(1, self.count)
        self.kind = ti.field(ti.i32, shape=n)
        self.position = ti.Vector.field(3, ti.f32, shape=n)
        self.direction = ti.Vector.field(3, ti.f32, shape=n)  # spot: axis; directional: travel
        self.value = ti.Vector.field(3, ti.f32, shape=n)  # intensity, or irradiance
        # spot: cos(cutoff), cos(beam), cutoff (radians), 1 / (cutoff - beam) (0: a hard edge)
        self.cone = ti.Vector.field(4, ti.f32, shape=n)
        if self.count:
            cone = np.zeros((n, 4))
            for i, s in enumerate(specs):
                if s.kind == "spot":
                    c, b = math.radians(s.cutoff_angle), math.radians(s.beam)
                    cone[i] = (math.cos(c), math.cos(b), c, 1.0 / (c - b) if c > b else 0.0)
            direction = np.array([s.direction for s in specs], np.float64)
            direction /= np.linalg.norm(direction, axis=1, keepdims=True)
            upload_fields([(self.kind, np.array([KIND_CODES[s.kind] for s in specs], np.int32)),
                           (self.position, np.array([s.position for s in specs], np.float32)),
                           (self.direction, direction.astype(np.float32)),
                           (self.value, np.array([s.irradiance if s.kind == "directional" else s.intensity
                                                  for s in specs], np.float32)),
                           (self.cone, cone.astype(np.float32))])
            self.selector = make_delta_selector(selector_kind, self.power)

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
    def sample(self, features: ti.template(), e, ref):
        """(wi, dist, value, position) of light e seen from ref: the unit direction towards it, the
        distance (INF for a directional light, whose position is then meaningless), the value
        that multiplies f / pmf (I falloff / r^2, or E), and the light's position."""
        wi = vec3(0.0, 0.0, 1.0)
        dist = INF
        value = vec3(0.0)
        position = ref
        k = self.kind[e]
        if ti.static(features.has_light("directional")):
            if k == DIRECTIONAL:
                wi = -self.direction[e]
                value = self.value[e]
        if ti.static(features.has_light("point") or features.has_light("spot")):
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
        return wi, dist, value, position

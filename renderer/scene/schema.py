"""The scene file format, as data: every section, field, type, default, range and meaning.

This module is the single source of truth. The TOML loader validates against it and
docs/scene-format.md is generated from it by `render_markdown()` (a test keeps the two equal).
Regenerate the document with:

    python -c "from renderer.scene.schema import write_markdown; write_markdown()"

Defaults here must equal the dataclass defaults in description.py; a test checks that too.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Optional

from renderer.materials.kinds import kinds_with_param
from renderer.materials.metals import metal_names
from renderer.sampling.names import SAMPLERS

from .description import (
    ENVIRONMENT_KINDS,
    GEOMETRY_KINDS,
    FOG_MODELS,
    MATERIAL_KINDS,
    MESH_GENERATORS,
    MESH_OBJECT_KINDS,
)


class _Required:
    """Marker default for fields that must be written in the file."""

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED = _Required()

# Key of the set of written field names in the values a section's Rule checks (see Rule).
WRITTEN = "<written>"

# Value kinds a field can have. The loader converts raw TOML values according to these.
VALUE_KINDS = {
    "bool": "true or false",
    "string": "string",
    "int": "integer",
    "float": "float",
    "vec3": "array of 3 floats",
    "dir3": "array of 3 floats",  # a direction: non-zero, normalised by the loader
    "int3": "array of 3 integers",
    "vec2": "array of 2 floats",
    "points2": "array of [float, float] pairs",
    "scale": "float, or array of 3 equal floats",
    "scale3": "float, or array of 3 floats",
    "table": "table",
    "tables": "array of tables",
}


def format_number(x: float) -> str:
    """Numbers as a person would write them: 1 rather than 1.0 in ranges and messages."""
    if isinstance(x, float) and x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    return repr(x)


@dataclass(frozen=True)
class Range:
    """A numeric interval (bounds may be open or absent) plus isolated extra values."""

    lo: Optional[float] = None
    hi: Optional[float] = None
    lo_open: bool = False
    hi_open: bool = False
    also: tuple[float, ...] = ()  # e.g. -1 for render.max_depth

    def __contains__(self, x: float) -> bool:
        if x in self.also:
            return True
        if self.lo is not None and (x < self.lo or (self.lo_open and x == self.lo)):
            return False
        if self.hi is not None and (x > self.hi or (self.hi_open and x == self.hi)):
            return False
        return True

    def __str__(self) -> str:
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            opening, closing = "(" if self.lo_open else "[", ")" if self.hi_open else "]"
            text = f"{opening}{format_number(lo)}, {format_number(hi)}{closing}"
        elif lo is not None:
            text = f"{'>' if self.lo_open else '>='} {format_number(lo)}"
        elif hi is not None:
            text = f"{'<' if self.hi_open else '<='} {format_number(hi)}"
        else:
            text = "any"
        extras = " or ".join(format_number(a) for a in self.also)
        return f"{extras} or {text}" if extras else text


POSITIVE = Range(0.0, lo_open=True)
NON_NEGATIVE = Range(0.0)
UNIT = Range(0.0, 1.0)
AT_LEAST_ONE = Range(1)

# Limits that keep a scene file from asking for more than a machine has (the memory a scene's
# files may take is budgeted separately: renderer/scene/limits.py).
MAX_IMAGE_SIDE = 16384  # pixels, as the command line's --size
FILM_SIDE = Range(1, MAX_IMAGE_SIDE)
# Operators may nest this deep (a top-level object is level 1). Each level of an operator tree
# is a func that Taichi inlines recursively in Python while compiling: a chain of 22 levels
# exhausts Python's recursion limit in the path tracer's kernel, 20 compile in every integrator.
MAX_SDF_DEPTH = 16
# Every number ends up as a 32-bit float on the device; larger magnitudes would become infinity.
F32_MAX = 3.4028234663852886e38


@dataclass(frozen=True)
class Field:
    name: str
    kind: str  # a key of VALUE_KINDS
    default: object
    description: str
    range: Optional[Range] = None  # applies to each component of a vector
    choices: Optional[tuple[str, ...]] = None
    only_for: Optional[tuple[str, ...]] = None  # the section `type`s this field belongs to
    attr: Optional[str] = None  # model attribute when it differs from `name`
    in_model: bool = True  # False: no model attribute of its own (e.g. emission_strength)
    default_doc: Optional[str] = None  # shown instead of the default when it is computed
    allowed_doc: Optional[str] = None  # shown instead of the range when another check applies
    geometries: Optional[tuple[str, ...]] = None  # the scene geometry kinds it belongs to (None: all)
    items: Optional[tuple["Field", ...]] = None  # kind "tables": the fields of each table

    @property
    def model_attr(self) -> str:
        return self.attr or self.name

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def applies_to(self, kind: Optional[str]) -> bool:
        return self.only_for is None or kind in self.only_for

    def in_geometry(self, geometry: str) -> bool:
        return self.geometries is None or geometry in self.geometries


@dataclass(frozen=True)
class Rule:
    """A constraint between fields. `check` gets the converted values (defaults filled in)
    and returns a problem description, or None when the values are fine. In a section's rules the
    values also hold, under WRITTEN, the names of the fields the file wrote (a default and the
    same value written out are not the same thing when fields exclude each other)."""

    text: str
    check: Callable[[dict], Optional[str]]


@dataclass(frozen=True)
class Section:
    name: str  # as written in the file, e.g. "render.march" or "materials.<name>"
    description: str
    fields: tuple[Field, ...]
    rules: tuple[Rule, ...] = ()
    heading: Optional[str] = None  # markdown heading, when the name alone is ambiguous

    def field(self, name: str) -> Field:
        return next(f for f in self.fields if f.name == name)

    def allowed(self, kind: Optional[str] = None) -> tuple[str, ...]:
        """Names of the fields a table of this section (of the given `type`) may contain."""
        return tuple(f.name for f in self.fields if f.applies_to(kind))


@dataclass(frozen=True)
class NodeKind:
    """An SDF primitive (no children) or operator (children)."""

    name: str
    description: str
    params: tuple[Field, ...] = ()
    rules: tuple[Rule, ...] = ()
    min_children: int = 0
    max_children: Optional[int] = 0  # None: no upper limit

    @property
    def is_operator(self) -> bool:
        return self.max_children != 0

    def children_text(self) -> str:
        if self.max_children == self.min_children:
            return f"exactly {self.min_children} child" + ("" if self.min_children == 1 else "ren")
        return f"at least {self.min_children} children"


@dataclass(frozen=True)
class MeshKind:
    """A `type` of object in a `mesh` scene: a model file, an analytic shape or a generated mesh."""

    name: str
    description: str
    params: tuple[Field, ...] = ()
    needs_material: bool = True  # False: the object may bring its own materials (model files)
    uniform_scale_reason: Optional[str] = None  # set when only a uniform scale keeps the shape
    rules: tuple[Rule, ...] = ()


@dataclass(frozen=True)
class Generator:
    """A procedural mesh of a `generated` object; its parameters are fields of that object."""

    name: str
    description: str
    params: tuple[Field, ...] = ()
    rules: tuple["Rule", ...] = ()


# --- rules -----------------------------------------------------------------------------------


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _norm(v) -> float:
    return math.sqrt(sum(c * c for c in v))


def _check_fixed_relaxation(v: dict) -> Optional[str]:
    if not v["adaptive"] and v["over_relaxation"] >= 2.0:
        return f"over_relaxation {v['over_relaxation']:g} needs adaptive = true (a fixed factor must be below 2)"
    return None


def _check_camera(v: dict) -> Optional[str]:
    view = tuple(b - a for a, b in zip(v["position"], v["look_at"]))
    if _norm(view) == 0.0:
        return "position and look_at are the same point"
    # Relative test so that tiny or huge scenes behave the same.
    if _norm(_cross(view, v["up"])) <= 1e-9 * _norm(view) * _norm(v["up"]):
        return "up is zero or parallel to the view direction (look_at - position)"
    return None


def _check_keyframes(v: dict) -> Optional[str]:
    keyframes = [dict(k) for k in v["keyframes"]]
    if not keyframes:
        return None
    if len(keyframes) < 2:
        return "keyframes: a camera path needs at least 2 keyframes, got 1"
    for i, k in enumerate(keyframes):
        if i and k["time"] <= keyframes[i - 1]["time"]:
            return (f"keyframes[{i}].time {format_number(k['time'])} is not after keyframes[{i - 1}].time "
                    f"{format_number(keyframes[i - 1]['time'])} (times must increase strictly)")
        view = {"position": k["position"], "look_at": k["look_at"], "up": k["up"] or v["up"]}
        problem = _check_camera(view)
        if problem:
            return f"keyframes[{i}]: {problem}"
    return None


def _check_rounded_box(v: dict) -> Optional[str]:
    half = min(v["size"]) / 2.0
    if v["radius"] > half:
        return (f"radius {format_number(v['radius'])} is larger than half the smallest size "
                f"component ({format_number(half)})")
    return None


def _check_profile(v: dict) -> Optional[str]:
    from renderer.geometry.bezier import profile_problem

    return profile_problem(v["profile"], v["degree"])


def _check_conductor_fresnel(v: dict) -> Optional[str]:
    if v["type"] != "conductor":
        return None
    if (v["eta"] is None) != (v["k"] is None):
        given, missing = ("eta", "k") if v["k"] is None else ("k", "eta")
        return f"`{given}` needs `{missing}` (the complex index eta + i k)"
    descriptions = (("`metal`", ("metal",)), ("`eta`/`k`", ("eta", "k")),
                    ("`base_color`/`edge_tint`", ("base_color", "edge_tint")))
    given = [name for name, fields in descriptions if v[WRITTEN] & set(fields)]
    if len(given) > 1:
        return (f"{', '.join(given[:-1])} and {given[-1]} cannot be combined: each describes the "
                "conductor's Fresnel (keep `metal`, or `eta` with `k`, or `base_color` with `edge_tint`)")
    return None


def _check_torus(v: dict) -> Optional[str]:
    if v["minor_radius"] >= v["major_radius"]:
        minor, major = format_number(v["minor_radius"]), format_number(v["major_radius"])
        return f"minor_radius {minor} must be smaller than major_radius {major}"
    return None


# --- sections --------------------------------------------------------------------------------

SCENE = Section(
    "scene",
    "What the file describes and which kind of geometry it holds. The section is required "
    "because `geometry` is.",
    (
        Field("name", "string", None, "Display name of the scene.", in_model=False,
              default_doc="the file name without extension"),
        Field("description", "string", "", "Free text, shown in tools and reports."),
        Field("geometry", "string", REQUIRED, "How objects are described. `sdf`: signed distance "
              "fields in `[[objects]]`. `mesh`: triangle meshes (model files and generated meshes), "
              "analytic spheres, discs and quads, and Bezier surfaces of revolution in `[[objects]]`.",
              choices=GEOMETRY_KINDS),
    ),
)

KEYFRAME_FIELDS = (
    Field("time", "float", REQUIRED, "When the camera is here, seconds from the animation's start.",
          default_doc="required"),
    Field("position", "vec3", REQUIRED, "Eye position, metres.", default_doc="required"),
    Field("look_at", "vec3", REQUIRED, "Point the camera looks at, metres.", default_doc="required"),
    Field("fov", "float", None, "Vertical field of view, degrees.", Range(1.0, 179.0),
          default_doc="the camera's `fov`"),
    Field("up", "vec3", None, "Up direction (need not be unit length).", default_doc="the camera's `up`"),
)

CAMERA = Section(
    "camera",
    "A thin-lens perspective camera. Every field is optional. The fields above `keyframes` are the "
    "camera of still renders and the viewer; `keyframes` adds a camera path for `render --frames` "
    "(README, Animations).",
    (
        Field("position", "vec3", (0.0, 1.0, 5.0), "Eye position, metres."),
        Field("look_at", "vec3", (0.0, 0.0, 0.0), "Point the camera looks at, metres."),
        Field("up", "vec3", (0.0, 1.0, 0.0), "Up direction (need not be unit length)."),
        Field("fov", "float", 45.0, "Vertical field of view, degrees.", Range(1.0, 179.0)),
        Field("aperture", "float", 0.0, "Lens radius, metres; 0 is a pinhole (no depth of field).",
              NON_NEGATIVE),
        Field("focus_distance", "float", 5.0, "Distance to the plane in focus, metres, along the "
              "view direction.", POSITIVE),
        Field("keyframes", "tables", (), "A camera path, one `[[camera.keyframes]]` table per keyframe "
              "(fields below). Between keyframes the position and look-at point follow a C1 Hermite "
              "spline in time (each inner keyframe's velocity from its neighbours, as non-uniform "
              "Catmull-Rom; zero at the first and last keyframe, so the camera eases in and out), the "
              "field of view a monotone one (it never leaves the range of the two keyframes around "
              "it), the up direction as the position; at a keyframe's time the camera is exactly the "
              "keyframe's. Before the first keyframe and after the last the camera holds it. The lens "
              "(`aperture`, `focus_distance`) stays the camera's.",
              default_doc="none (a still camera)", allowed_doc="see below", items=KEYFRAME_FIELDS),
    ),
    (Rule("`position` and `look_at` must differ, and `up` must not be parallel to the view "
          "direction.", _check_camera),
     Rule("A camera path has at least 2 keyframes, their times increase strictly, and each keyframe's "
          "`position`, `look_at` and `up` obey the rule above.", _check_keyframes)),
)

RENDER = Section(
    "render",
    "Image size, sampling and integrator. Every field is optional.",
    (
        Field("width", "int", 640, "Image width, pixels.", FILM_SIDE),
        Field("height", "int", 360, "Image height, pixels.", FILM_SIDE),
        Field("spp", "int", 64, "Samples per pixel.", AT_LEAST_ONE),
        Field("max_depth", "int", 8, "Longest path, in segments: 1 shows emitters seen directly, "
              "2 adds direct light, and so on. -1 means unlimited (Russian roulette ends paths).",
              Range(1, also=(-1,))),
        Field("integrator", "string", "mis", "Integrator name, checked against the integrators "
              "the renderer provides."),
        Field("seed", "int", 0, "Random seed; the same seed gives the same image.", NON_NEGATIVE),
        Field("sampler", "string", "independent", "Where random numbers come from: `independent` "
              "(hashed uniform numbers) or `sobol` (Owen-scrambled Sobol points, lower error at equal spp).",
              choices=SAMPLERS),
        Field("energy_compensation", "bool", True, "Give rough metals and rough glass back the light "
              "that single-scattering microfacet models lose between microfacets (Kulla and Conty 2017): "
              "without it a white metal of roughness 1 reflects 31% head-on, and a white glass ball of "
              "roughness 0.5 in a white furnace looks 18% too dark. It also layers the `principled` "
              "diffuse base under its coat so that nothing is lost between them. Mitsuba 3 and pbrt "
              "have none of this: set it to false to compare rough materials with them. Only scenes "
              "with `conductor`, `dielectric` or `principled` materials compile it."),
        Field("march", "table", None, "Sphere-tracing settings, see `[render.march]`.",
              in_model=False, default_doc="see below", allowed_doc="see below",
              geometries=("sdf",)),
    ),
)

MARCH = Section(
    "render.march",
    "Sphere-tracing settings of `sdf` scenes (an error in `mesh` scenes, which do not sphere "
    "trace). Every field is optional.",
    (
        Field("hit_threshold", "float", 1.0, "A ray hits when the distance is below this many "
              "pixel footprints at that range.", POSITIVE),
        Field("min_threshold", "float", 1e-4, "Absolute floor on the hit distance, metres.",
              POSITIVE),
        Field("max_steps", "int", 256, "Most steps along one ray before it counts as a miss.",
              AT_LEAST_ONE),
        Field("max_distance", "float", 100.0, "Rays stop after this distance, metres.", POSITIVE),
        Field("over_relaxation", "float", 3.0, "The longest step, in distance bounds; 1 is plain "
              "sphere tracing. A longer step is kept only if the unbounding spheres of its ends overlap "
              "(else the marcher steps back), so no step crosses a surface. Steps beyond 2 bounds are "
              "only taken by `adaptive` marching, where the distance grows along the ray (rays leaving "
              "the scene); a fixed factor must stay below 2.", Range(1.0, 4.0, hi_open=True)),
        Field("adaptive", "bool", True, "Choose each step from the distance's slope along the ray "
              "(Bán and Valasek 2023), up to `over_relaxation`; false uses `over_relaxation` as a "
              "fixed factor (Keinert et al. 2014), which must then be below 2."),
    ),
    rules=(Rule("With `adaptive = false`, `over_relaxation` must be below 2: a fixed factor of 2 or "
                "more overshoots every surface it approaches.", _check_fixed_relaxation),),
)

_MAP, _SKY, _CONSTANT = ("map",), ("sky",), ("constant",)

ENVIRONMENT = Section(
    "environment",
    "Light arriving from infinitely far away. A field that belongs to another `type` is an error.",
    (
        Field("type", "string", "sky", "Kind of environment.", choices=ENVIRONMENT_KINDS,
              attr="kind"),
        Field("file", "string", REQUIRED, "Image file, `.exr` or `.hdr` (latitude-longitude). A "
              "relative path is relative to the scene file's folder.", only_for=_MAP,
              default_doc="required", allowed_doc="an existing `.exr` or `.hdr` file"),
        Field("intensity", "float", 1.0, "Multiplier on the emitted radiance.", NON_NEGATIVE),
        Field("rotation", "float", 0.0, "Rotation of the map about +y, degrees, by the right-hand rule "
              "(counter-clockwise seen from above): Mitsuba's `to_world` rotate([0, 1, 0], rotation). "
              "The map itself is oriented as Mitsuba's `envmap` (see conventions.md)."),
        Field("color", "vec3", (1.0, 1.0, 1.0), "Uniform radiance, linear RGB.", NON_NEGATIVE,
              only_for=_CONSTANT),
        Field("zenith", "vec3", (0.25, 0.45, 0.9), "Sky radiance straight up, linear RGB.",
              NON_NEGATIVE, only_for=_SKY),
        Field("horizon", "vec3", (0.9, 0.9, 1.0), "Sky radiance at the horizon, linear RGB.",
              NON_NEGATIVE, only_for=_SKY),
        Field("ground", "vec3", (0.3, 0.28, 0.25), "Radiance from below the horizon, linear RGB.",
              NON_NEGATIVE, only_for=_SKY),
    ),
)


def _kind_fields(fields: tuple[Field, ...]) -> tuple[Field, ...]:
    """A material's fields, each with the kinds it belongs to as the registry says (fields no
    kind claims belong to every kind)."""
    return tuple(replace(f, only_for=kinds_with_param(f.name) or None) for f in fields)


GLASSES_CHOICES = ("bk7", "fused_silica", "sf11", "water")  # renderer/spectral/ior.py SELLMEIER_PRESETS

MATERIAL = Section(
    "materials.<name>",
    "One table per material; the key is the material's name, which objects refer to. Materials "
    "that no object uses are allowed. `principled` follows glTF's metallic-roughness model: a "
    "dielectric base (diffuse plus a specular layer with the given `ior`) blended with a metal of "
    "colour `base_color` by `metallic`, and a `transmission` fraction of the dielectric base that "
    "refracts instead of scattering diffusely. `null` is an invisible boundary: light passes "
    "straight through it (a path still counts it as a vertex); with `medium` it bounds a "
    "participating medium such as smoke in a box.",
    _kind_fields((
        Field("type", "string", "diffuse", "Kind of material.", choices=MATERIAL_KINDS, attr="kind"),
        Field("base_color", "vec3", (0.8, 0.8, 0.8), "Albedo (diffuse), reflectance at normal "
              "incidence (conductor), transmission tint (dielectric) or glTF base colour "
              "(principled), linear RGB.", UNIT),
        Field("edge_tint", "vec3", (1.0, 1.0, 1.0), "A conductor's tint near grazing angles: the "
              "Fresnel curve from `base_color` (reflectance at normal incidence) is scaled to "
              "`edge_tint` times Schlick's value at 82 degrees (Hoffman's F82 model). 1 is plain "
              "Schlick.", UNIT),
        Field("eta", "vec3", None, "A conductor's complex index of refraction eta + i k, real part, "
              "per RGB channel (as Mitsuba's `conductor` `eta`): the Fresnel is then the exact one of "
              "that index instead of `base_color` and `edge_tint`. Needs `k`.", Range(0.0, 100.0),
              default_doc="none"),
        Field("k", "vec3", None, "The imaginary part (extinction coefficient) of that index, per RGB "
              "channel. Needs `eta`.", Range(0.0, 100.0), default_doc="none"),
        Field("metal", "string", "", "A measured metal by name: its RGB `eta` and `k` as Mitsuba 3's "
              "RGB variants derive them from its spectra (every Mitsuba preset, such as `Au`, `Ag`, "
              "`Al`, `Cu`, `Cr`, `W`, `Ni_palik`, plus `Fe`, `Ni`, `Ti` from Johnson and Christy 1974 "
              "and `Pt` from Rakic et al. 1998; renderer/materials/data/metals.csv lists them with "
              "their sources).", choices=metal_names(), default_doc="none",
              allowed_doc="a name in renderer/materials/data/metals.csv"),
        Field("metallic", "float", 0.0, "0 is a dielectric base, 1 a metal (glTF "
              "`metallicFactor`).", UNIT),
        Field("roughness", "float", 0.5, "Perceptual roughness; 0 is a perfect mirror.", UNIT),
        Field("transmission", "float", 0.0, "Fraction of the dielectric base that is transmitted "
              "(glTF `KHR_materials_transmission`).", UNIT),
        Field("ior", "float", 1.5, "Index of refraction.", Range(1.0, 4.0, lo_open=True)),
        Field("thin", "bool", False, "A thin-walled transmitter: a shell with no inside (a soap "
              "bubble, a window pane modelled as one surface, glTF transmission without "
              "`KHR_materials_volume`). Light reflects off it or passes straight through; it is not "
              "bent and does not travel inside."),
        Field("clearcoat", "float", 0.0, "Weight of a clear coat over the material (glTF "
              "`KHR_materials_clearcoat`): a dielectric layer of index 1.5 whose reflection is added "
              "on top, and what it does not reflect reaches the layers below.", UNIT),
        Field("clearcoat_roughness", "float", 0.0, "Perceptual roughness of the clear coat.", UNIT),
        Field("sheen_color", "vec3", (0.0, 0.0, 0.0), "Colour of a sheen layer (glTF "
              "`KHR_materials_sheen`): the soft retro-reflection of velvet and cloth (Charlie "
              "distribution). Black is no sheen.", UNIT),
        Field("sheen_roughness", "float", 0.0, "Perceptual roughness of the sheen.", UNIT),
        Field("specular", "float", 1.0, "Strength of the dielectric base's specular reflection (glTF "
              "`KHR_materials_specular` `specularFactor`); what it does not reflect goes to the "
              "diffuse base.", UNIT),
        Field("specular_color", "vec3", (1.0, 1.0, 1.0), "Colour of that specular reflection "
              "(`specularColorFactor`).", UNIT),
        Field("emission", "vec3", (0.0, 0.0, 0.0), "Emitted radiance, linear RGB.", NON_NEGATIVE),
        Field("emission_strength", "float", 1.0, "Multiplier folded into `emission`.",
              NON_NEGATIVE, in_model=False),
        Field("abbe", "float", 0.0, "Dispersion: the Abbe number of the glass (about 64 for crown "
              "glass, 25-35 for flint, lower disperses more); the index then follows a Cauchy curve "
              "through `ior` at 587.6 nm. 0 is no dispersion. A dispersive material makes the scene "
              "render spectrally (hero wavelengths).", NON_NEGATIVE),
        Field("glass", "string", "", "Dispersion of a real glass from its published Sellmeier "
              "coefficients: `bk7`, `fused_silica`, `sf11` or `water`; replaces `ior` and `abbe`.",
              choices=GLASSES_CHOICES, default_doc="none"),
        Field("medium", "string", "", "Name of a `[media]` entry that fills the inside of surfaces "
              "made of this material: paths that cross the surface inwards (by refraction, or "
              "through a `null` surface) travel in it. Media do not nest.",
              default_doc="none", allowed_doc="a defined medium"),
    )),
    rules=(Rule("A conductor's Fresnel comes from one description: `base_color` with `edge_tint`, or "
                "`eta` with `k`, or `metal`; fields of two of them together are an error, and `eta` and "
                "`k` come together.", _check_conductor_fresnel),),
)

MEDIUM = Section(
    "media.<name>",
    "Homogeneous participating media (fog, smoke, murky liquid), one table per medium; materials "
    "(`medium`) and `[fog]` refer to them by name. Light is absorbed and scattered along the way "
    "with the Henyey-Greenstein phase function. Scenes without media compile no medium code.",
    (
        Field("sigma_a", "vec3", (0.0, 0.0, 0.0), "Absorption coefficient per metre, RGB.", NON_NEGATIVE),
        Field("sigma_s", "vec3", (0.1, 0.1, 0.1), "Scattering coefficient per metre, RGB.", NON_NEGATIVE),
        Field("g", "float", 0.0, "Henyey-Greenstein asymmetry: 0 scatters evenly, towards 1 "
              "forwards, towards -1 backwards.", Range(-0.99, 0.99)),
    ),
)

FOG = Section(
    "fog",
    "What fills the space between objects. `type = 'medium'`: the named medium fills the whole scene (the "
    "camera sits in it; light from the environment arrives through it, attenuated to nothing from "
    "infinitely far away, so light such scenes with emitters). `type = 'analytic'`: the exponential blend "
    "of real-time renderers, colour = mix(`color`, radiance, exp(-`density` distance)) along "
    "camera rays: a named approximation that assumes the same in-scattered light everywhere (no "
    "shadows or light shafts), cheap and not physically based.",
    (
        Field("type", "string", "none", "Kind of fog.", choices=FOG_MODELS, attr="model"),
        Field("medium", "string", REQUIRED, "The medium that fills the scene.", only_for=("medium",),
              default_doc="required", allowed_doc="a defined medium"),
        Field("density", "float", 0.1, "Extinction per metre of the analytic fog.", NON_NEGATIVE,
              only_for=("analytic",)),
        Field("color", "vec3", (0.7, 0.75, 0.8), "The colour distance fades to, linear RGB.",
              NON_NEGATIVE, only_for=("analytic",)),
    ),
)

# Fields every [[objects]] node may have, whatever its type.
NODE = Section(
    "objects",
    "The SDF objects of an `sdf` scene, one `[[objects]]` table each; a scene needs at least one. "
    "The object types of `mesh` scenes (other than `sphere`) are errors here. "
    "An object is a primitive or an operator whose operands are written as "
    "`[[objects.children]]` tables (nested to any depth: `[[objects.children.children]]`). "
    "Every node may carry a transform, applied as scale, then rotation, then translation. "
    "In error messages nodes are named by 0-based position, e.g. `objects[1].children[0]`.",
    (
        Field("type", "string", REQUIRED, "A primitive or operator name, see below.",
              allowed_doc="see below"),
        Field("material", "string", REQUIRED, "Name of a material defined under `[materials]`. "
              "Required on top-level objects and not allowed on children, which use their "
              "top-level object's material.", default_doc="required (top level only)",
              allowed_doc="a defined material"),
        Field("translate", "vec3", (0.0, 0.0, 0.0), "Translation, metres."),
        Field("rotate", "vec3", (0.0, 0.0, 0.0), "Euler angles, degrees, applied about x, then "
              "y, then z."),
        Field("scale", "scale", 1.0, "Uniform scale. Three equal numbers are accepted; unequal "
              "ones are an error, because a non-uniform scale breaks the distance bound.",
              POSITIVE),
        Field("children", "tables", None, "Operands of an operator (operators only).",
              default_doc="none", allowed_doc="see the operator"),
    ),
    heading="`[[objects]]` in `sdf` scenes",
)


def _length(name: str, default: float, text: str) -> Field:
    return Field(name, "float", default, text, POSITIVE)


PRIMITIVES = (
    NodeKind("sphere", "A sphere centred at the origin.",
             (_length("radius", 0.5, "Radius."),)),
    NodeKind("box", "An axis-aligned box centred at the origin.",
             (Field("size", "vec3", (1.0, 1.0, 1.0), "Full edge lengths along x, y, z.", POSITIVE),)),
    NodeKind("rounded_box", "A box with rounded edges; `size` is the outer size.",
             (Field("size", "vec3", (1.0, 1.0, 1.0), "Full edge lengths along x, y, z.", POSITIVE),
              _length("radius", 0.1, "Edge rounding radius.")),
             (Rule("`radius` must be at most half the smallest `size` component.",
                   _check_rounded_box),)),
    NodeKind("torus", "A ring in the xz plane, centred at the origin.",
             (_length("major_radius", 0.5, "Distance from the centre to the tube's centre line."),
              _length("minor_radius", 0.15, "Tube radius.")),
             (Rule("`minor_radius` must be smaller than `major_radius`.", _check_torus),)),
    NodeKind("capsule", "A segment along y, centred at the origin, swept by a sphere.",
             (_length("height", 1.0, "Length of the core segment (the caps add `radius` at each end)."),
              _length("radius", 0.25, "Radius."))),
    NodeKind("cylinder", "A capped cylinder along y, centred at the origin.",
             (_length("height", 1.0, "Full height."),
              _length("radius", 0.5, "Radius."))),
    NodeKind("cone", "A capped cone along y: base at y = -height/2, apex at y = +height/2.",
             (_length("height", 1.0, "Full height."),
              _length("radius", 0.5, "Base radius."))),
    NodeKind("plane", "The infinite plane dot(p, normal) = offset; the solid side is the one "
             "the normal points away from.",
             (Field("normal", "dir3", (0.0, 1.0, 0.0), "Plane normal; normalised on load.",),
              Field("offset", "float", 0.0, "Signed distance of the plane from the origin, metres."))),
)

OPERATORS = (
    NodeKind("union", "Everything inside any child.", min_children=2, max_children=None),
    NodeKind("intersection", "Only what is inside every child.", min_children=2, max_children=None),
    NodeKind("subtraction", "The first child minus all the others.", min_children=2,
             max_children=None),
    NodeKind("smooth_union", "A union whose seams are blended.",
             (_length("k", 0.1, "Blend radius, metres."),), min_children=2, max_children=None),
    NodeKind("repeat", "Copies of its child on a grid.",
             (Field("period", "vec3", (1.0, 1.0, 1.0), "Grid spacing along x, y, z, metres; 0 "
                    "means no repetition along that axis.", NON_NEGATIVE),
              Field("limit", "int3", None, "Finite repetition: `[lx, ly, lz]` gives 2l+1 copies "
                    "along each axis. Absent: infinite repetition.", NON_NEGATIVE,
                    default_doc="none (infinite)")),
             min_children=1, max_children=1),
)

NODE_KINDS = {k.name: k for k in PRIMITIVES + OPERATORS}

# --- mesh scenes -----------------------------------------------------------------------------

# Model file formats `load_mesh_asset` reads (renderer.scene.model_formats.MESH_EXTENSIONS; a test
# keeps the two equal). The scene loader checks the extension and that the file exists; the file
# itself is read when the scene is prepared for rendering.
MESH_FILE_EXTENSIONS = (".gltf", ".glb", ".obj", ".ply", ".stl")

MESH_OBJECT = Section(
    "objects",
    "The objects of a `mesh` scene, one `[[objects]]` table each; a scene needs at least one. "
    "`type` says what the object is (see below); SDF primitives and operators are errors here. "
    "Every object may carry a transform, applied as scale, then rotation, then translation. "
    "In error messages objects are named by 0-based position, e.g. `objects[1]`.",
    (
        Field("type", "string", REQUIRED, "An object type, see below.", choices=MESH_OBJECT_KINDS),
        Field("material", "string", None, "Name of a material defined under `[materials]`. "
              "Required, except for `mesh` objects, where it replaces every material of the model "
              "file (without it the file's own materials are used).",
              default_doc="required (optional for `mesh`)", allowed_doc="a defined material"),
        Field("translate", "vec3", (0.0, 0.0, 0.0), "Translation, metres."),
        Field("rotate", "vec3", (0.0, 0.0, 0.0), "Euler angles, degrees, applied about x, then "
              "y, then z."),
        Field("scale", "scale3", 1.0, "Scale factor: one number (uniform) or one per axis. "
              "`sphere` and `disc` need a uniform scale.", POSITIVE),
    ),
    heading="`[[objects]]` in `mesh` scenes",
)

MESH_KINDS = (
    MeshKind("mesh", "Triangle meshes from a model file, with the file's materials and textures "
             "unless `material` overrides them. The file is placed as its node hierarchy "
             "places it, then transformed by the object's transform.",
             (Field("file", "string", REQUIRED, "Model file, `.gltf`, `.glb`, `.obj`, `.ply` or "
                    "`.stl`. A relative path is relative to the scene file's folder.",
                    default_doc="required", allowed_doc="an existing model file"),),
             needs_material=False),
    MeshKind("sphere", "An analytic sphere centred at the origin.",
             (Field("radius", "float", 0.5, "Radius.", POSITIVE),),
             uniform_scale_reason="an ellipsoid is not a sphere"),
    MeshKind("quad", "A rectangle in the local xz plane, centred at the origin, facing +y "
             "(its front side, which matters for emitters, is the +y side).",
             (Field("size", "vec2", (1.0, 1.0), "Full edge lengths along local x and z.",
                    POSITIVE),)),
    MeshKind("disc", "A disc in the local xz plane, centred at the origin, facing +y.",
             (Field("radius", "float", 0.5, "Radius.", POSITIVE),),
             uniform_scale_reason="an ellipse is not a disc"),
    MeshKind("generated", "A triangle mesh made by a procedural generator (see Generators "
             "below) when the scene is loaded for rendering; the generator's parameters are "
             "fields of the object.",
             (Field("generator", "string", REQUIRED, "Which generator.",
                    choices=MESH_GENERATORS, default_doc="required"),)),
    MeshKind("bezier", "A surface of revolution: a profile curve made of Bezier segments, in the "
             "local (radius, height) plane, revolved about the local y axis (the transform places "
             "that axis). Intersected exactly (Newton iteration on the surface, no tessellation); "
             "texture u runs along the profile (an equal share per segment), v around the axis from "
             "+x towards +z, and the tangent follows u. Normals point away from the axis where "
             "the profile climbs: list a closed outline counter-clockwise in the (radius, height) "
             "plane, up the outside and back down the inside, for outward normals (which "
             "glass needs). An emissive Bezier surface glows where paths hit it, but direct "
             "lighting does not sample it.",
             (Field("profile", "points2", REQUIRED, "Control points `[radius, height]`, metres: "
                    "`degree` + 1 for the first segment and `degree` more for each further one "
                    "(a segment starts where the previous one ends). Radius 0 is on the axis.",
                    default_doc="required", allowed_doc="see the rule below"),
              Field("degree", "int", 3, "Degree of every segment: 1 (straight lines), 2 or 3.",
                    Range(1, 3)),
              Field("spans", "int", 4, "Patches per segment along the profile; a patch is split "
                    "further until the profile turns by at most 30 degrees within it.",
                    Range(1, 64)),
              Field("sectors", "int", 16, "Patches around the axis.", Range(4, 256))),
             rules=(Rule("`profile` needs `degree` x k + 1 points (k >= 1 segments), radii >= 0, and "
                         "no segment that is a single point or lies on the axis.", _check_profile),)),
)

MESH_KINDS_BY_NAME = {k.name: k for k in MESH_KINDS}

WAVE_FIELDS = (
    Field("direction", "float", 0.0, "Direction of travel, degrees from +x towards +z."),
    Field("wavelength", "float", REQUIRED, "Crest-to-crest distance, metres.", POSITIVE,
          default_doc="required"),
    Field("amplitude", "float", REQUIRED, "Height of a crest above the mean level, metres.",
          NON_NEGATIVE, default_doc="required"),
    Field("phase", "float", 0.0, "Phase offset, degrees."),
    Field("steepness", "float", 0.0, "Gerstner steepness Q: 0 is a sine wave; toward 1 the crests "
          "sharpen and the troughs flatten (1: circular orbits).", UNIT),
)

WATER_RANDOM_FIELDS = ("wave_count", "wavelength", "amplitude", "direction", "spread", "steepness", "seed")


def _water_defaults() -> dict:
    spec = next(g for g in GENERATORS if g.name == "water")
    return {f.name: f.default for f in spec.params}


def _check_water_fields(v: dict) -> Optional[str]:
    if not v["waves"]:
        return None
    defaults = _water_defaults()
    given = [name for name in WATER_RANDOM_FIELDS if v[name] != defaults[name]]
    if given:
        return (f"{', '.join(given)} describe{'s' if len(given) == 1 else ''} a random wave set and "
                f"cannot be combined with `waves` (remove {'it' if len(given) == 1 else 'them'} or the waves)")
    return None


def _check_water_waves(v: dict) -> Optional[str]:
    from renderer.scene import waves  # numpy only; imported here to keep the schema light

    wave_set, names = waves.from_params(v)
    return waves.problems(wave_set, v["size"] / v["resolution"], names)


GENERATORS = (
    Generator("terrain", "A height field over a square grid in the local xz plane, centred at "
              "the origin: `resolution` x `resolution` quads (2 triangles each, so 708 gives "
              "1,002,528 triangles) with heights from seeded fractal value noise, in "
              "[-`height`, +`height`].",
              (Field("resolution", "int", 708, "Quads along each side.", Range(2, 4096)),
               Field("size", "float", 10.0, "Edge length of the square, metres.", POSITIVE),
               Field("height", "float", 1.0, "Largest height above or below y = 0, metres.",
                     NON_NEGATIVE),
               Field("seed", "int", 0, "Noise seed; the same seed gives the same terrain.",
                     NON_NEGATIVE))),
    Generator("icosphere", "A sphere made of triangles: an icosahedron subdivided "
              "`subdivisions` times (20 * 4^subdivisions triangles), centred at the origin.",
              (Field("subdivisions", "int", 3, "Subdivision steps.", Range(0, 8)),
               Field("radius", "float", 1.0, "Radius, metres.", POSITIVE))),
    Generator("light_panels", "Many small emitters: `count_x` x `count_z` square panels (2 "
              "triangles each, so the defaults give 20,000 triangles) in the plane y = `height`, "
              "facing down (-y), one at the centre of each cell of a `size` x `size` grid "
              "centred on the y axis, moved by a small seeded jitter (at most a quarter of the "
              "gap between panel and cell, so panels stay apart). Give the object an emissive "
              "material; panels larger than their cell overlap.",
              (Field("count_x", "int", 100, "Panels along x.", Range(1, 1000)),
               Field("count_z", "int", 100, "Panels along z.", Range(1, 1000)),
               Field("size", "float", 20.0, "Edge length of the square the panels cover, metres.",
                     POSITIVE),
               Field("panel_size", "float", 0.05, "Edge length of one panel, metres.", POSITIVE),
               Field("height", "float", 3.0, "Height of the panels' plane (local y), metres."),
               Field("seed", "int", 0, "Jitter seed; the same seed gives the same panels.",
                     NON_NEGATIVE))),
    Generator("water", "A water surface: a `resolution` x `resolution` grid of quads (2 triangles "
              "each) over a `size` x `size` square in the local xz plane, centred at the origin, "
              "displaced by a sum of directional Gerstner waves (heights from cosines, crests "
              "sharpened by moving points toward them; see `renderer/scene/waves.py`), with analytic "
              "vertex normals facing +y. The waves are the `waves` tables, or, without them, a random "
              "set drawn from `seed`. The border moves inward by up to the sum of steepness times "
              "amplitude: let the grid reach into the walls around it. Give it a `dielectric` "
              "material (water: `ior = 1.33`) for refraction and caustics.",
              (Field("resolution", "int", 256, "Quads along each side.", Range(2, 2048)),
               Field("size", "float", 4.0, "Edge length of the square, metres.", POSITIVE),
               Field("waves", "tables", (), "The waves, one table each (fields below). Absent or "
                     "empty: a random set from the fields that follow.", default_doc="none (a random set)",
                     allowed_doc="see below", items=WAVE_FIELDS),
               Field("wave_count", "int", 4, "Random set: how many waves.", Range(1, 64)),
               Field("wavelength", "float", 1.0, "Random set: the longest wavelength, metres; the "
                     "others are log-uniform down to a quarter of it.", POSITIVE),
               Field("amplitude", "float", 0.02, "Random set: the amplitude of a wave `wavelength` "
                     "long, metres; shorter waves are proportionally lower (equally steep).",
                     NON_NEGATIVE),
               Field("direction", "float", 0.0, "Random set: mean direction of travel, degrees "
                     "from +x towards +z."),
               Field("spread", "float", 30.0, "Random set: directions are uniform within "
                     "`direction` +- `spread`, degrees.", Range(0.0, 180.0)),
               Field("steepness", "float", 0.5, "Random set: the Gerstner steepness of every wave.",
                     UNIT),
               Field("seed", "int", 0, "Random set: the seed; the same seed gives the same waves.",
                     NON_NEGATIVE)),
              (Rule("`waves` and the random-set fields (`wave_count`, `wavelength`, `amplitude`, "
                    "`direction`, `spread`, `steepness`, `seed`) exclude each other.", _check_water_fields),
               Rule("Every wavelength spans at least two grid cells (2 * `size` / `resolution`), and "
                    "the sum over the waves of steepness * 2 pi * amplitude / wavelength stays below 1 "
                    "(else Gerstner crests loop and the surface intersects itself).", _check_water_waves))),
)

GENERATORS_BY_NAME = {g.name: g for g in GENERATORS}

# Top-level sections, in the order the documentation presents them.
TOP_LEVEL = ("scene", "camera", "render", "environment", "materials", "media", "fog", "objects")
SECTIONS = (SCENE, CAMERA, RENDER, MARCH, ENVIRONMENT, MATERIAL, MEDIUM, FOG)

ENV_MAP_EXTENSIONS = (".exr", ".hdr")
SCENE_EXTENSIONS = (".toml",)


# --- documentation ---------------------------------------------------------------------------

INTRO = """\
# Scene file format

A scene is a [TOML](https://toml.io) file with the extension `.toml`. Units are metres and
angles are degrees. Colours are linear RGB. Relative file paths (such as an environment map)
are relative to the folder of the scene file.

A scene holds one kind of geometry, named by `[scene] geometry`: `sdf` (signed distance
fields, sphere traced) or `mesh` (triangle meshes with a BVH, plus analytic spheres, discs and
quads, and Bezier surfaces of revolution). The two kinds share `[camera]`, `[render]`, `[environment]` and `[materials]`; they differ
in what `[[objects]]` may hold, and `[render.march]` belongs to `sdf` scenes only.

Only `[scene]` (for its `geometry` field) and at least one object are required; every other
field has the default listed below. The loader is strict: an unknown section or field, a value
of the wrong type (including `true`/`false` where a number is expected), a vector of the wrong
length, `nan` or `inf`, or a value out of range is an error. Every error is one line naming the
file and the place in it, for example:

```text
assets/scenes/x.toml: unknown material 'golde' in objects[2] (known: gold, floor)
assets/scenes/x.toml: materials.glass: unknown field 'iorr' (allowed: type, base_color, roughness, ior, emission, emission_strength)
```

Coming from another renderer? [conventions.md](conventions.md) lists what to match to
reproduce a Mitsuba 3 or pbrt scene: perceptual roughness, the Smith masking term, two-sided
materials, the pixel filter, the environment map's orientation, energy compensation, metals.

This document is generated from `renderer/scene/schema.py`; edit that file, then run
`python -c "from renderer.scene.schema import write_markdown; write_markdown()"`.
"""

EXAMPLE = """\
[scene]
name = "showcase"
description = "A gold sphere and a glass blob on a floor, lit by a park."
geometry = "sdf"

[camera]
position = [0, 1.2, 5]
look_at = [0, 0.5, 0]
fov = 40
aperture = 0.02
focus_distance = 5.0

[render]
width = 960
height = 540
spp = 128
max_depth = -1
integrator = "mis"
seed = 7

[render.march]
max_steps = 400
over_relaxation = 1.5

[environment]
type = "map"
file = "../envmaps/park.exr"
intensity = 1.2
rotation = 90

[materials.gold]
type = "conductor"
base_color = [1.0, 0.78, 0.34]
roughness = 0.2

[materials.glass]
type = "dielectric"
base_color = [1, 1, 1]
roughness = 0.0
ior = 1.5

[materials.floor]
base_color = [0.6, 0.6, 0.6]
roughness = 0.8

[materials.lamp]
emission = [1.0, 0.9, 0.8]
emission_strength = 5.0

[[objects]]
type = "sphere"
material = "gold"
radius = 0.5
translate = [-1, 0.5, 0]

[[objects]]
type = "smooth_union"
material = "glass"
k = 0.2
translate = [1, 0.6, 0]
rotate = [0, 45, 0]
[[objects.children]]
type = "rounded_box"
size = [0.8, 0.8, 0.8]
radius = 0.1
[[objects.children]]
type = "sphere"
radius = 0.5
translate = [0, 0.4, 0]

[[objects]]
type = "repeat"
material = "lamp"
period = [2, 0, 2]
limit = [2, 0, 2]
translate = [0, 3, 0]
[[objects.children]]
type = "torus"
major_radius = 0.3
minor_radius = 0.05

[[objects]]
type = "plane"
material = "floor"
normal = [0, 1, 0]
offset = 0
"""


MESH_EXAMPLE = """\
[scene]
name = "bunny on a table"
description = "A model file, analytic shapes and a generated mesh."
geometry = "mesh"

[camera]
position = [0, 1.5, 4]
look_at = [0, 0.5, 0]
fov = 35

[render]
width = 640
height = 360
spp = 64
max_depth = 8

[environment]
type = "map"
file = "../envmaps/sky.exr"

[materials.copper]
type = "conductor"
base_color = [0.955, 0.638, 0.538]
roughness = 0.25

[materials.plastic]
type = "principled"
base_color = [0.1, 0.3, 0.8]
metallic = 0.0
roughness = 0.3
ior = 1.45

[materials.floor]
base_color = [0.5, 0.5, 0.5]

[materials.lamp]
base_color = [0, 0, 0]
emission = [1, 0.9, 0.8]
emission_strength = 10

[[objects]]
type = "mesh"
file = "../models/bunny.glb"
material = "copper"
translate = [0, 0.45, 0]
rotate = [0, 30, 0]
scale = 0.5

[[objects]]
type = "sphere"
material = "plastic"
radius = 0.3
translate = [1, 0.3, 0]

[[objects]]
type = "quad"
material = "floor"
size = [20, 20]

[[objects]]
type = "disc"
material = "lamp"
radius = 0.5
translate = [0, 3, 0]
rotate = [180, 0, 0]

[[objects]]
type = "generated"
generator = "terrain"
material = "floor"
resolution = 64
size = 20
height = 0.3
seed = 1
translate = [0, -0.35, -15]
scale = [1, 1, 0.5]
"""


def _format_value(value: object) -> str:
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(_format_value(v) for v in value) + "]"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def _default_text(f: Field) -> str:
    if f.default_doc is not None:
        return f.default_doc
    if f.required:
        return "required"
    return f"`{_format_value(f.default)}`"


def _allowed_text(f: Field) -> str:
    if f.allowed_doc is not None:
        return f.allowed_doc
    parts = []
    if f.choices:
        parts.append(", ".join(f"`\"{c}\"`" for c in f.choices))
    if f.kind == "dir3":
        parts.append("non-zero")
    if f.range is not None:
        each = "each component " if f.kind in ("vec3", "vec2", "int3", "dir3", "scale3") else ""
        parts.append(f"{each}{f.range}")
    return "; ".join(parts) or "any"


def _description_text(f: Field) -> str:
    text = f.description
    if f.only_for:
        kinds = " or ".join(f'`type = "{k}"`' for k in f.only_for)
        text += f" Only with {kinds}."
    if f.geometries:
        kinds = " or ".join(f"`{g}`" for g in f.geometries)
        text += f" Only in {kinds} scenes."
    return text


def _field_table(fields: tuple[Field, ...]) -> list[str]:
    lines = ["| Field | Type | Default | Allowed | Description |",
             "| --- | --- | --- | --- | --- |"]
    for f in fields:
        lines.append(f"| `{f.name}` | {VALUE_KINDS[f.kind]} | {_default_text(f)} | "
                     f"{_allowed_text(f)} | {_description_text(f)} |")
    return lines


def _rules_list(rules: tuple[Rule, ...]) -> list[str]:
    return ["", *(f"- {r.text}" for r in rules)] if rules else []


def _section_heading(section: Section) -> str:
    return section.heading if section.heading is not None else f"`[{section.name}]`"


def _items_markdown(fields: tuple[Field, ...]) -> list[str]:
    """The fields of each table of a field of tables (a camera's keyframes, a water surface's waves)."""
    lines = []
    for f in fields:
        if f.items:
            lines += ["", f"Each table of `{f.name}`:", "", *_field_table(f.items)]
    return lines


def _section_markdown(section: Section) -> list[str]:
    return ["", f"## {_section_heading(section)}", "", section.description, "",
            *_field_table(section.fields), *_items_markdown(section.fields), *_rules_list(section.rules)]


def _node_kind_markdown(kind: NodeKind) -> list[str]:
    lines = ["", f"#### `{kind.name}`", "", kind.description]
    if kind.is_operator:
        lines[-1] += f" Takes {kind.children_text()}."
    if kind.params:
        lines += ["", *_field_table(kind.params)]
    else:
        lines += ["", "No parameters."]
    return lines + _rules_list(kind.rules)


def _mesh_kind_markdown(kind: MeshKind) -> list[str]:
    lines = ["", f"#### `{kind.name}`", "", kind.description]
    notes = []
    if kind.needs_material:
        notes.append("Needs `material`.")
    if kind.uniform_scale_reason:
        notes.append(f"Needs a uniform `scale` ({kind.uniform_scale_reason}).")
    if notes:
        lines[-1] += " " + " ".join(notes)
    return lines + ["", *_field_table(kind.params), *_rules_list(kind.rules)]


def _generator_markdown(generator: Generator) -> list[str]:
    return ["", f"#### `{generator.name}`", "", generator.description, "",
            *_field_table(generator.params), *_items_markdown(generator.params), *_rules_list(generator.rules)]


def render_markdown() -> str:
    """The complete text of docs/scene-format.md."""
    lines = [INTRO.rstrip("\n")]
    for section in SECTIONS:
        lines += _section_markdown(section)
    lines += _section_markdown(NODE)
    lines += ["", "### Primitives", "",
              "Primitives sit in their own frame, centred at the origin; y is the axis where "
              "there is one. Lengths must be greater than 0."]
    for kind in PRIMITIVES:
        lines += _node_kind_markdown(kind)
    lines += ["", "### Operators"]
    for kind in OPERATORS:
        lines += _node_kind_markdown(kind)
    lines += _section_markdown(MESH_OBJECT)
    lines += ["", "### Object types", "",
              "Analytic shapes and generated meshes sit in their own frame, centred at the "
              "origin. Lengths must be greater than 0. A field of another type is an error."]
    for kind in MESH_KINDS:
        lines += _mesh_kind_markdown(kind)
    lines += ["", "### Generators", "",
              "The parameters of the chosen `generator` are written as fields of its "
              "`generated` object; a parameter of another generator is an error. Generators "
              "are deterministic: the same parameters give the same mesh."]
    for generator in GENERATORS:
        lines += _generator_markdown(generator)
    lines += ["", "## Complete examples", "",
              "With the scenes in `assets/scenes/`, the maps in `assets/envmaps/` and the models "
              "in `assets/models/`. An `sdf` scene:", "",
              "```toml", EXAMPLE.rstrip("\n"), "```", "",
              "A `mesh` scene:", "",
              "```toml", MESH_EXAMPLE.rstrip("\n"), "```"]
    return "\n".join(lines) + "\n"


# docs/scene-format.md, found from this file: renderer/scene/schema.py -> repository root.
DOC_PATH = Path(__file__).resolve().parents[2] / "docs" / "scene-format.md"


def write_markdown(path: Path = DOC_PATH) -> None:
    Path(path).write_text(render_markdown(), encoding="utf-8")

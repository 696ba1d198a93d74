"""The registry of material kinds and of the principled model's layers (numpy side, no Taichi).

A kind is what a scene file's `type` names. Its entry says its id in the device table (its
position in KINDS), the scene-file parameters that belong to it, its own defaults of shared ones
(metals and glass are smooth), its device columns, the lobe flags its BSDF can have (pbrt's
BxDFFlags) and the module holding its lobes, which renderer/materials/bsdf.py dispatches to. The layers of the principled kind (glTF clearcoat,
sheen, specular) are entries of their own: parameters, columns, flags and the test of a device
row that says whether the row uses the layer. Features holds the sets of kinds and layers a
scene uses, and only those are compiled.

Adding a kind: a lobe module with `sample`, `evaluate` and `flags` (see renderer/materials/diffuse.py),
one MaterialKind entry here, and its tests. Adding a layer: the layer's code in the principled
model behind `ti.static(features.has_layer(name))` and one MaterialLayer entry here.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


class LobeFlags:
    """pbrt-v4's BxDFFlags, bits of an int: which scattering a BSDF can do. A kind's entry holds
    the bits it can have; its lobe module's `flags(bsdf, mat)` says which a material has."""

    REFLECTION = 1
    TRANSMISSION = 2
    DIFFUSE = 4
    GLOSSY = 8
    SPECULAR = 16
    NON_DELTA = DIFFUSE | GLOSSY  # what `eval` can return and light sampling can use


# Only roughness == 0 is a delta lobe. Any other roughness is clamped to at least this GGX width so
# that D(h) <= 1/(pi a^2) ~ 3e7 stays finite in f32.
MIN_ALPHA = 1e-4


def alpha_from_roughness(roughness: float) -> float:
    """A microfacet width alpha from a perceptual roughness (0 stays a delta lobe)."""
    return 0.0 if roughness == 0.0 else max(roughness * roughness, MIN_ALPHA)


NO_TEXTURE = -1
MAX_MIX_DEPTH = 4  # mixes within mixes: how deep shading follows them (MaterialSpec.mix)
NO_MEDIUM = -1
SCENE_MEDIUM = -2  # a material's outside_medium: whatever surrounds every object (the fog's medium)
NO_TABLE = -1
# Sidedness, one property for every reader: a surface shades alike from both sides (Lantern's and
# glTF's doubleSided), its back face is black (Mitsuba's one-sided BSDFs), or its back face is
# not there at all (glTF's doubleSided: false, back-face culling).
SIDEDNESS = {"two_sided": 0, "back_black": 1, "back_culled": 2}
TWO_SIDED, BACK_BLACK, BACK_CULLED = 0, 1, 2
# Microfacet models (renderer/materials/microfacet.py): the distribution and the masking form.
MICROFACET_MODELS = {"ggx": 0, "ggx_separable": 1, "beckmann": 2}
# How the texture in a row's normal slot (textures[2]) tilts the shading normal: a glTF
# tangent-space normal map (scaled by normal_scale), Mitsuba's normalmap (a normal in the shading
# frame) or Mitsuba's bumpmap (a height field, its gradient times normal_scale); the last two with
# Mitsuba's flipping and shadow-terminator term (renderer/materials/mapped_frames.py).
NORMAL_MAP_MODELS = {"tangent_space": 0, "shading_frame": 1, "height": 2}
TANGENT_SPACE_MAP, SHADING_FRAME_MAP, HEIGHT_MAP = 0, 1, 2


@dataclass(frozen=True)
class Column:
    """One member of the device table's row. type: "i32", "f32", "vec3", "vec4" or "ivec4";
    default: the value of a row that does not set it; from_spec: read from the MaterialSpec
    attribute of the same name (scene files); gltf: the PbrMaterial attribute it is read from
    (model files; None: set by the table's own code or left at its default)."""

    name: str
    type: str
    default: object
    from_spec: bool = False
    gltf: str | None = None


@dataclass(frozen=True)
class MaterialKind:
    """name: the scene file's `type`; label: its name in the HUD and `info`; params: the
    scene-file fields that belong to it (others are errors on it); columns: its own device
    columns (shared ones may be listed by several kinds); flags: the LobeFlags it can have;
    lobes: the module of its `sample`, `evaluate` and `flags` (Taichi funcs); compensation: when
    Kulla-Conty multiple scattering is compiled for it ("always", "rough": where a row's
    roughness > 0, "never"); refracts: its transmission bends light into another index (radiance scales by
    1 / eta^2, photons do not); defaults: (field, value) pairs for the scene-file fields whose default
    differs on this kind from the field's shared one."""

    name: str
    label: str
    params: tuple[str, ...]
    columns: tuple[Column, ...]
    flags: int
    lobes: str
    compensation: str = "never"
    refracts: bool = False
    defaults: tuple[tuple[str, object], ...] = ()


@dataclass(frozen=True)
class MaterialLayer:
    """A layer of a kind (`of`): its scene-file params, device columns, flags, and `in_use(row)`
    on a numpy row of the table (a scene whose rows do not use it compiles none of its code)."""

    name: str
    of: str
    params: tuple[str, ...]
    columns: tuple[Column, ...]
    flags: int
    in_use: Callable[[dict], bool]


_F = LobeFlags
_IOR = Column("ior", "f32", 1.5, from_spec=True)
_THIN = Column("thin", "i32", 0)
# A tint of the specular reflection: the glTF specular layer's colour, a plastic's coating's and a
# conductor's Fresnel's (Mitsuba's specular_reflectance); its texture: specular_color_texture.
_SPECULAR_COLOR = Column("specular_color", "vec3", (1.0, 1.0, 1.0), from_spec=True, gltf="specular_color_factor")
_CLEARCOAT = Column("clearcoat", "f32", 0.0, from_spec=True, gltf="clearcoat_factor")  # principled's layer, disney's lobe
# The roughness of a material that names none, unless its kind has its own: what `principled`
# starts from in Blender and Mitsuba 3 (diffuse and null surfaces ignore it).
SHARED_ROUGHNESS = 0.5
# Metals, glass and plastics are smooth unless a roughness is given, as in Mitsuba 3 and pbrt-v4.
_SMOOTH = (("roughness", 0.0),)

# Shared by every kind: what the base of any surface has (colour, roughness, emission, the
# base texture slots, the medium inside, glTF coverage).
SHARED_COLUMNS = (
    Column("kind", "i32", 0),
    Column("base_color", "vec3", (0.8, 0.8, 0.8), from_spec=True),
    Column("roughness", "f32", SHARED_ROUGHNESS, from_spec=True),
    Column("emission", "vec3", (0.0, 0.0, 0.0), from_spec=True),
    Column("normal_scale", "f32", 1.0),  # a height map's: its scale
    Column("textures", "ivec4", (NO_TEXTURE,) * 4),  # base colour, metallic-roughness, normal, emissive
    Column("normal_map_model", "i32", TANGENT_SPACE_MAP),  # NORMAL_MAP_MODELS: what the normal slot holds
    Column("medium", "i32", NO_MEDIUM),
    Column("outside_medium", "i32", SCENE_MEDIUM),
    Column("two_sided_emission", "i32", 0, from_spec=True),  # emission from both faces (else the front's)  # crossing outwards leads here (SCENE_MEDIUM: the scene's)
    Column("alpha_mode", "i32", 0),
    Column("alpha_cutoff", "f32", 0.5),
    Column("base_alpha", "f32", 1.0),
    # The layers' texture slots: (clearcoat, clearcoat roughness, sheen colour, sheen roughness)
    # and (specular, specular colour, clearcoat normal, unused).
    Column("layer_textures", "ivec4", (NO_TEXTURE,) * 4),
    Column("layer_textures2", "ivec4", (NO_TEXTURE,) * 4),
    # The microfacet model of the kinds that have one (renderer/materials/microfacet.py MODELS)
    # and the sidedness (SIDEDNESS); set by the table's code from the spec's names.
    Column("microfacet", "i32", 0),
    Column("sidedness", "i32", TWO_SIDED),
    # Anisotropic roughness: the width along the surface's dp/dv (roughness is along dp/du); below
    # 0 the material is isotropic.
    Column("roughness_v", "f32", -1.0),
    Column("alpha_textures", "ivec4", (NO_TEXTURE,) * 4),  # alpha (along u), alpha_v, unused, unused
    Column("opacity_texture", "i32", NO_TEXTURE),  # coverage from a texture's first channel (Mitsuba's mask)
    Column("specular_color_texture", "i32", NO_TEXTURE),  # multiplies specular_color (conductors, plastics)
    Column("index_textures", "ivec4", (NO_TEXTURE,) * 4),  # multiply a complex index's eta and k; unused, unused
    # A mix row (MaterialSpec.mix): the rows of its two materials, its weight's texture slot, unused;
    # -1 in the first: not a mix.
    Column("mix", "ivec4", (-1, -1, NO_TEXTURE, NO_TEXTURE)),
    Column("mix_weight", "f32", 0.5, from_spec=True),
)

# Disney's principled BSDF as Mitsuba 3 has it (renderer/materials/disney.py): its parameters
# of its own (metallic, transmission = spec_trans, clearcoat, ior and thin are shared columns), and
# the texture slots of its scalar parameters, in the order of the columns disney_textures,
# disney_textures2 and disney_textures3 (MaterialSpec.parameter_textures gives them by name).
DISNEY_PARAMS = ("anisotropic", "sheen", "sheen_tint", "spec_tint", "clearcoat_gloss", "flatness", "diff_trans",
                 "front_both_sides")
DISNEY_TEXTURED = ("roughness", "anisotropic", "metallic", "sheen", "sheen_tint", "spec_tint", "clearcoat",
                   "clearcoat_gloss", "flatness", "diff_trans", "transmission")

KINDS = (
    MaterialKind("diffuse", "diffuse", (), (), _F.REFLECTION | _F.DIFFUSE, "renderer.materials.diffuse"),
    MaterialKind("conductor", "conductor", ("edge_tint", "eta", "k", "metal", "microfacet", "roughness_v",
                                            "specular_color"),
                 (Column("edge_tint", "vec3", (1.0, 1.0, 1.0), from_spec=True), Column("complex_ior", "i32", 0),
                  _SPECULAR_COLOR,
                  Column("eta", "vec3", (0.0, 0.0, 0.0)), Column("k", "vec3", (0.0, 0.0, 0.0)),
                  Column("fresnel_avg", "vec3", (0.0, 0.0, 0.0))),
                 _F.REFLECTION | _F.GLOSSY | _F.SPECULAR, "renderer.materials.conductor", compensation="rough",
                 defaults=_SMOOTH),
    MaterialKind("dielectric", "glass", ("ior", "thin", "abbe", "glass", "microfacet", "roughness_v",
                                        "specular_color"),
                 (_IOR, _THIN, _SPECULAR_COLOR, Column("dispersion", "i32", 0), Column("dispersion_b", "vec4", (0.0,) * 4),
                  Column("dispersion_c", "vec4", (0.0,) * 4)),
                 _F.REFLECTION | _F.TRANSMISSION | _F.GLOSSY | _F.SPECULAR, "renderer.materials.dielectric",
                 compensation="rough", refracts=True, defaults=_SMOOTH),
    MaterialKind("principled", "principled", ("metallic", "transmission", "ior", "thin"),
                 (Column("metallic", "f32", 0.0, from_spec=True), Column("transmission", "f32", 0.0, from_spec=True),
                  _IOR, _THIN, Column("transmission_texture", "i32", NO_TEXTURE)),
                 _F.REFLECTION | _F.TRANSMISSION | _F.DIFFUSE | _F.GLOSSY | _F.SPECULAR,
                 "renderer.materials.principled", compensation="always", refracts=True),
    MaterialKind("null", "null surfaces", (), (), _F.TRANSMISSION | _F.SPECULAR, "renderer.materials.null_boundary"),
    # Mitsuba 3's plastic and roughplastic: a diffuse base under a smooth or rough dielectric
    # coating, its internal reflections summed in closed form (renderer/materials/plastic.py).
    MaterialKind("plastic", "plastic", ("ior", "nonlinear", "specular_color", "microfacet"),
                 (_IOR, Column("nonlinear", "i32", 0), _SPECULAR_COLOR,
                  Column("plastic_table", "i32", NO_TABLE), Column("internal_reflectance", "f32", 0.0),
                  Column("specular_weight", "f32", 0.5)),
                 _F.REFLECTION | _F.DIFFUSE | _F.GLOSSY | _F.SPECULAR, "renderer.materials.plastic",
                 defaults=_SMOOTH),
    # Disney's principled BSDF (Burley 2012, 2015) exactly as Mitsuba 3's `principled` and, thin,
    # its `principledthin` define it: diffuse with retro-reflection, fake subsurface (flatness) and
    # sheen, an anisotropic GGX specular with tint, a GTR1 clear coat, a rough specular
    # transmission (spec_trans) and, thin, a diffuse transmission. No lobe is a delta.
    MaterialKind("disney", "Disney principled",
                 ("metallic", "transmission", "ior", "thin", "clearcoat", *DISNEY_PARAMS),
                 (Column("metallic", "f32", 0.0, from_spec=True), Column("transmission", "f32", 0.0, from_spec=True),
                  _IOR, _THIN, Column("transmission_texture", "i32", NO_TEXTURE),
                  _CLEARCOAT,
                  *(Column(name, "f32", 0.0, from_spec=True) for name in DISNEY_PARAMS[:-1]),
                  Column("disney_textures", "ivec4", (NO_TEXTURE,) * 4),
                  Column("disney_textures2", "ivec4", (NO_TEXTURE,) * 4),
                  Column("disney_textures3", "ivec4", (NO_TEXTURE,) * 4),
                  Column("front_both_sides", "i32", 0, from_spec=True)),
                 _F.REFLECTION | _F.TRANSMISSION | _F.DIFFUSE | _F.GLOSSY, "renderer.materials.disney",
                 refracts=True),
    # pbrt-v4's coateddiffuse and coatedconductor (coat_base): a dielectric interface (ior, roughness,
    # roughness_v) over a diffuse (base_color) or conductor (eta, k or metal; conductor_roughness)
    # base, a scattering slab between; f and pdf are pbrt's random-walk estimates
    # (renderer/materials/coated.py).
    MaterialKind("coated", "coated (pbrt)", ("ior", "roughness_v", "coat_base", "coat_thickness", "coat_albedo",
                                             "coat_g", "coat_maxdepth", "coat_nsamples", "conductor_roughness",
                                             "eta", "k", "metal"),
                 (_IOR, Column("coat_base", "i32", 0), Column("coat_thickness", "f32", 0.01, from_spec=True),
                  Column("coat_albedo", "vec3", (0.0, 0.0, 0.0), from_spec=True),
                  Column("coat_g", "f32", 0.0, from_spec=True), Column("coat_maxdepth", "i32", 10, from_spec=True),
                  Column("coat_nsamples", "i32", 1, from_spec=True),
                  Column("conductor_roughness", "f32", 0.0, from_spec=True), Column("complex_ior", "i32", 0),
                  Column("eta", "vec3", (0.0, 0.0, 0.0)), Column("k", "vec3", (0.0, 0.0, 0.0)),
                  Column("fresnel_avg", "vec3", (0.0, 0.0, 0.0))),
                 _F.REFLECTION | _F.DIFFUSE | _F.GLOSSY | _F.SPECULAR, "renderer.materials.coated", defaults=_SMOOTH),
    # pbrt-v4's diffusetransmission: Lambert reflection (base_color) and Lambert transmission
    # (transmittance, its texture in parameter_textures) through a sheet without an inside.
    MaterialKind("diffuse_transmission", "diffuse transmission", ("transmittance",),
                 (Column("transmittance", "vec3", (0.2, 0.2, 0.2), from_spec=True),
                  Column("transmittance_texture", "i32", NO_TEXTURE)),
                 _F.REFLECTION | _F.TRANSMISSION | _F.DIFFUSE, "renderer.materials.diffuse_transmission"),
)

LAYERS = (
    MaterialLayer("clearcoat", "principled", ("clearcoat", "clearcoat_roughness"),
                  (_CLEARCOAT,
                   Column("clearcoat_roughness", "f32", 0.0, from_spec=True, gltf="clearcoat_roughness_factor"),
                   Column("clearcoat_normal_scale", "f32", 1.0, gltf="clearcoat_normal_scale")),
                  _F.REFLECTION | _F.GLOSSY | _F.SPECULAR,
                  lambda r: r["kind"] == KIND_IDS["principled"] and r["clearcoat"] > 0.0),
    MaterialLayer("sheen", "principled", ("sheen_color", "sheen_roughness"),
                  (Column("sheen_color", "vec3", (0.0, 0.0, 0.0), from_spec=True, gltf="sheen_color_factor"),
                   Column("sheen_roughness", "f32", 0.0, from_spec=True, gltf="sheen_roughness_factor")),
                  _F.REFLECTION | _F.GLOSSY, lambda r: max(r["sheen_color"]) > 0.0),
    # Strength and colour scale the base's dielectric Fresnel: in use where they differ from
    # glTF's defaults (1, white) or a texture varies them.
    MaterialLayer("specular", "principled", ("specular", "specular_color"),
                  (Column("specular", "f32", 1.0, from_spec=True, gltf="specular_factor"),
                   _SPECULAR_COLOR),
                  _F.REFLECTION | _F.GLOSSY | _F.SPECULAR,
                  lambda r: r["kind"] == KIND_IDS["principled"] and (
                      r["specular"] != 1.0 or min(r["specular_color"]) != 1.0
                      or r["layer_textures2"][0] != NO_TEXTURE or r["layer_textures2"][1] != NO_TEXTURE)),
)

KIND_NAMES = tuple(k.name for k in KINDS)
KIND_IDS = {k.name: i for i, k in enumerate(KINDS)}
LAYER_NAMES = tuple(layer.name for layer in LAYERS)
NULL_KIND = KIND_IDS["null"]  # the integrators let paths cross null boundaries


def _unique(columns) -> tuple[Column, ...]:
    seen = {}
    for c in columns:
        seen.setdefault(c.name, c)
    return tuple(seen.values())


# Every device column once: the shared ones, then each kind's and each layer's, in registry order.
COLUMNS = _unique((*SHARED_COLUMNS, *(c for k in KINDS for c in k.columns),
                   *(c for layer in LAYERS for c in layer.columns)))
LAYER_COLUMNS = tuple(c for layer in LAYERS for c in layer.columns)


def kind(name: str) -> MaterialKind:
    return KINDS[KIND_IDS[name]]


def kinds_with_param(param: str) -> tuple[str, ...]:
    """The kinds a scene-file field belongs to (their own parameters or their layers'), in
    registry order."""
    return tuple(k.name for k in KINDS if param in k.params
                 or any(layer.of == k.name and param in layer.params for layer in LAYERS))


def own_defaults(param: str) -> dict[str, object]:
    """The kinds that give a scene-file field a default of their own, with that default, in
    registry order."""
    return {k.name: dict(k.defaults)[param] for k in KINDS if param in dict(k.defaults)}


def default_on(name: str, param: str, shared: object) -> object:
    """A scene-file field's default on a material of kind `name`: the kind's own, else `shared`."""
    return dict(kind(name).defaults).get(param, shared)


def compensated_when_rough(name: str) -> bool:
    return kind(name).compensation == "rough"


def always_compensated(name: str) -> bool:
    return kind(name).compensation == "always"

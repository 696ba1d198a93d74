"""The scene file format, as data: every section, field, type, default, range and meaning.

These tables are the format's single source of truth. The TOML loader validates against them (the
checks of their rules are schema_checks.py) and docs/scene-format.md is generated from them
(schema_docs.py; a test keeps the two equal). The types they are made of are schema_types.py.

Defaults here must equal the dataclass defaults in description.py; a test checks that too.
"""
from __future__ import annotations

from dataclasses import replace

from renderer.materials.kinds import MICROFACET_MODELS, SHARED_ROUGHNESS, SIDEDNESS, kinds_with_param, own_defaults
from renderer.materials.coat_bases import COAT_BASES
from renderer.materials.metals import metal_names
from renderer.film.filter_keys import PIXEL_FILTERS
from renderer.sampling.names import SAMPLERS
from renderer.scene.textures import TEXTURE_FILTERS

from .description import (
    ENVIRONMENT_KINDS,
    GEOMETRY_KINDS,
    FOG_MODELS,
    FOV_AXES,
    LIGHT_KINDS,
    MATERIAL_KINDS,
    MEDIUM_KINDS,
    MESH_GENERATORS,
    MESH_OBJECT_KINDS,
    PROJECTIONS,
)
from .schema_checks import (
    check_camera,
    check_conductor_fresnel,
    check_crop,
    check_one_surface_map,
    check_fixed_relaxation,
    check_keyframes,
    check_light_up,
    check_spot_beam,
    check_profile,
    check_rounded_box,
    check_torus,
    check_water_waves,
    water_fields_check,
)
from .schema_model_materials import MODEL_MATERIAL
from .schema_types import (
    AT_LEAST_ONE,
    EXPOSURE_EV,
    NON_NEGATIVE,
    POSITIVE,
    REQUIRED,
    UNIT,
    Field,
    Generator,
    MeshKind,
    NodeKind,
    Range,
    Rule,
    Section,
)

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
        Field("edits", "string", None, "Makes the file a scene of edits: a Mitsuba 3 (`.xml`), pbrt-v4 "
              "(`.pbrt`) or model file, relative to this one, read as it is; the file then holds only "
              "`[scene]` (`edits`, `description`), and `[materials.<name>]`, `[environment]`, "
              "`[lights.<i>]` and `[model_materials.<i>]` tables with the values that change (a material by its name in that file, a "
              "light by its 0-based place; fields not written keep the file's; a light keeps its type "
              "and image). The viewer saves its edits of such scenes this way.", in_model=False,
              default_doc="none"),
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
    "A thin-lens perspective or orthographic camera. Every field is optional. The fields above `keyframes` are the "
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
        Field("projection", "string", "perspective", "`perspective`: rays leave the eye through the "
              "field of view. `orthographic`: parallel rays along the view direction, from a plane "
              "through `position` `ortho_height` tall (its width follows the image's aspect); `fov` "
              "is then unused.", choices=PROJECTIONS),
        Field("ortho_height", "float", 2.0, "The height of an orthographic view, metres.", POSITIVE),
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
          "direction.", check_camera),
     Rule("A camera path has at least 2 keyframes, their times increase strictly, and each keyframe's "
          "`position`, `look_at` and `up` obey the rule above.", check_keyframes)),
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
        Field("pixel_filter", "string", "box", "The reconstruction filter: `box` (each sample in its own "
              "pixel), `tent` (radius `filter_radius`) or `gaussian` (deviation `filter_stddev`, cut off at four "
              "deviations: Mitsuba's default filter). Samples are drawn from the filter, so each pixel stays an "
              "unbiased mean.", choices=PIXEL_FILTERS),
        Field("filter_radius", "float", 1.0, "The tent filter's radius, pixels.", POSITIVE),
        Field("filter_stddev", "float", 0.5, "The Gaussian filter's standard deviation, pixels.", POSITIVE),
        Field("crop", "int4", None, "`[x, y, width, height]`: render and write only this window of the "
              "`width` x `height` image, in pixels from its top-left corner (Mitsuba's hdrfilm crop). The "
              "projection stays the whole image's, and each pixel of the window is the same pixel of the "
              "whole render (its rays, its pixel filter at the image's edges and its random numbers), so "
              "crops of one image tile it (`sppm`'s photon passes, shared by the window's pixels, depend on "
              "its size). The viewer shows the window scaled to fit, centred.",
              NON_NEGATIVE, default_doc="none (the whole image)"),
        Field("exposure", "float", 0.0, "Exposure in EV stops for what is displayed: PNG output and the "
              "viewer scale radiance by 2^exposure before tone mapping; EXR output keeps radiance. `render "
              "--exposure` and the viewer's slider override it. A pbrt-v4 film's `iso` and the camera's "
              "shutter time set it (log2 of shutter time x iso / 100, pbrt-v4's imaging ratio).",
              EXPOSURE_EV),
        Field("energy_compensation", "bool", True, "Give rough metals and rough glass back the light "
              "that single-scattering microfacet models lose between microfacets (Kulla and Conty 2017): "
              "without it a white metal of roughness 1 reflects 31% head-on, and a white glass ball of "
              "roughness 0.5 in a white furnace looks 18% too dark. It also layers the `principled` "
              "diffuse base under its coat so that nothing is lost between them. Mitsuba 3 and pbrt "
              "have none of this: set it to false to compare rough materials with them. Only scenes "
              "with `conductor`, `dielectric` or `principled` materials compile it."),
        Field("texture_filter", "string", "anisotropic", "How textures are read over the patch of surface "
              "a pixel sees: `anisotropic` (mip-mapped at the patch's shorter side, with up to 8 lookups along "
              "the longer), `trilinear` (mip-mapped at its longer side: cheaper, and blurry where surfaces are "
              "seen at grazing angles) or `none` (the image itself, bilinear or nearest as each texture says). "
              "The patch is the pixel's ray cone, which narrows as a pixel's samples accumulate, so filtering "
              "smooths the first samples (no shimmering textures at 1 spp) and the converged image tends to "
              "the unfiltered one. Only `mesh` scenes with textures compile it.", choices=TEXTURE_FILTERS),
        Field("march", "table", None, "Sphere-tracing settings, see `[render.march]`.",
              in_model=False, default_doc="see below", allowed_doc="see below",
              geometries=("sdf",)),
    ),
    (Rule("A `crop` window has at least one pixel and lies within the `width` x `height` image.", check_crop),),
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
                "more overshoots every surface it approaches.", check_fixed_relaxation),),
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
        Field("rotation", "float", 0.0, "Rotation of the map (or the sky) about `rotation_axis`, degrees, "
              "by the right-hand rule (about +y: counter-clockwise seen from above): Mitsuba's `to_world` "
              "rotate(rotation_axis, rotation). The map itself is oriented as Mitsuba's `envmap` (see "
              "conventions.md)."),
        Field("rotation_axis", "dir3", (0.0, 1.0, 0.0), "The axis `rotation` turns about; normalised "
              "on load. Any axis but +y or -y tilts the map's poles, which compiles a 3x3 rotation into "
              "the environment's lookups and sampling (a turn about +y is an offset in azimuth)."),
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
    """A material's fields, each with the kinds it belongs to and the kinds' own defaults as the
    registry says (fields no kind claims belong to every kind)."""
    return tuple(replace(f, only_for=kinds_with_param(f.name) or None,
                         type_defaults=tuple(own_defaults(f.name).items())) for f in fields)


GLASSES_CHOICES = ("bk7", "fused_silica", "sf11", "water")  # renderer/spectral/ior.py SELLMEIER_PRESETS
# Images a material's normal or bump map may be (what the texture reader decodes).
MAP_IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".tif", ".tiff", ".webp", ".exr")

MATERIAL = Section(
    "materials.<name>",
    "One table per material; the key is the material's name, which objects refer to. Materials "
    "that no object uses are allowed. `principled` follows glTF's metallic-roughness model: a "
    "dielectric base (diffuse plus a specular layer with the given `ior`) blended with a metal of "
    "colour `base_color` by `metallic`, and a `transmission` fraction of the dielectric base that "
    "refracts instead of scattering diffusely. `disney` is Disney's principled BSDF as Mitsuba 3's "
    "`principled` (with `thin`, its `principledthin`) defines it: `metallic`, `transmission` (Disney's "
    "`spec_trans`), `clearcoat`, `ior` and `thin` with its own fields below; the index comes from `ior` "
    "(Disney's `specular` s is the index 2 / (1 - sqrt(0.08 s)) - 1). `null` is an invisible boundary: light passes "
    "straight through it (crossing it is no bounce: `max_depth` does not count it, as in Mitsuba and "
    "pbrt); with `medium` it bounds a participating medium such as smoke in a box.",
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
        Field("roughness", "float", SHARED_ROUGHNESS, "Perceptual roughness; 0 is a perfect mirror (and "
              "clear glass). Conductors and dielectrics are smooth unless a roughness is given, as in "
              "Mitsuba 3 and pbrt; `principled` starts from 0.5, as in Blender and Mitsuba 3 (a glTF "
              "material's roughness is its own, 1 when the file gives none).", UNIT),
        Field("transmission", "float", 0.0, "Fraction of the dielectric base that is transmitted "
              "(glTF `KHR_materials_transmission`).", UNIT),
        Field("ior", "float", 1.5, "Index of refraction.", Range(1.0, 4.0, lo_open=True)),
        Field("thin", "bool", False, "A thin-walled transmitter: a shell with no inside (a soap "
              "bubble, a window pane modelled as one surface, glTF transmission without "
              "`KHR_materials_volume`). Light reflects off it or passes straight through; it is not "
              "bent and does not travel inside. Passing a smooth one is no bounce (`max_depth` does "
              "not count it) and shadow rays pass it; with `medium` it bounds that medium."),
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
              "(`specularColorFactor`); on a `plastic` its coating's tint, on a `conductor` a tint of its "
              "Fresnel, on a `dielectric` its reflection's tint (Mitsuba's `specular_reflectance`).", UNIT),
        Field("anisotropic", "float", 0.0, "`disney`: stretches the specular lobe along the surface's "
              "texture direction u (widths roughness^2 / a and roughness^2 a along u and v, a = sqrt(1 - 0.9 "
              "anisotropic)). Mesh scenes with texture coordinates.", UNIT),
        Field("sheen", "float", 0.0, "`disney`: weight of the sheen, a soft grazing reflection for cloth.", UNIT),
        Field("sheen_tint", "float", 0.0, "`disney`: how far the sheen takes the base colour's hue.", UNIT),
        Field("spec_tint", "float", 0.0, "`disney`: how far the dielectric specular takes the base colour's "
              "hue.", UNIT),
        Field("clearcoat_gloss", "float", 0.0, "`disney`: gloss of the clear coat (GTR1 width 0.1 at 0, 0.001 "
              "at 1).", UNIT),
        Field("flatness", "float", 0.0, "`disney`: blends the diffuse towards a flatter, subsurface-like "
              "response (Hanrahan-Krueger).", UNIT),
        Field("diff_trans", "float", 0.0, "`disney` with `thin`: diffuse transmission, 0 to 2 (1: half the "
              "diffuse light passes through the sheet).", Range(0.0, 2.0)),
        Field("front_both_sides", "bool", False, "`disney`: the back face shades as the front (Mitsuba's "
              "`twosided` around a `principled`); otherwise the back is the model's inside, dark unless it "
              "transmits."),
        Field("microfacet", "string", "ggx", "The microfacet model of a rough conductor, dielectric or "
              "plastic: `ggx` (Smith's height-correlated masking), `ggx_separable` or `beckmann` "
              "(Smith's separable masking, as Mitsuba 3 has them). Energy compensation applies to "
              "`ggx` only.", choices=tuple(MICROFACET_MODELS)),
        Field("roughness_v", "float", None, "Anisotropic roughness: the perceptual roughness along the "
              "surface's texture direction v (dp/dv), `roughness` being the one along u (Mitsuba's "
              "`alpha_u` and `alpha_v` are their squares). Mesh scenes with texture coordinates.",
              UNIT, geometries=("mesh",), default_doc="none (isotropic)"),
        Field("nonlinear", "bool", False, "A plastic whose base colour deepens under its coating "
              "(Mitsuba's `nonlinear`: the light the coating reflects back to the base is tinted "
              "by it again)."),
        Field("coat_base", "string", "diffuse", "`coated`: the base under the coat, `diffuse` (reflectance "
              "`base_color`) or `conductor` (`eta` and `k` or `metal`; copper if none).",
              choices=tuple(COAT_BASES)),
        Field("coat_thickness", "float", 0.01, "`coated`: the slab's thickness, in units of its mean free "
              "path (pbrt's `thickness`).", Range(0.0, 1e6)),
        Field("coat_albedo", "vec3", (0.0, 0.0, 0.0), "`coated`: single-scattering albedo of the medium in "
              "the slab; black: no medium, only its transmittance.", UNIT),
        Field("coat_g", "float", 0.0, "`coated`: Henyey-Greenstein asymmetry of that medium.", Range(-1.0, 1.0)),
        Field("coat_maxdepth", "int", 10, "`coated`: longest random walk in the slab.", AT_LEAST_ONE),
        Field("coat_nsamples", "int", 1, "`coated`: random walks per evaluation.", AT_LEAST_ONE),
        Field("transmittance", "vec3", (0.2, 0.2, 0.2), "`diffuse_transmission`: colour of the Lambert "
              "transmission to the other side (`base_color` is the reflection's); with `base_color` at "
              "most 1 per channel for a sheet that keeps no more light than it receives.", UNIT),
        Field("conductor_roughness", "float", 0.0, "`coated` with a conductor base: the conductor's "
              "perceptual roughness.", UNIT),
        Field("sidedness", "string", "two_sided", "`two_sided`: both sides shade alike; "
              "`back_black`: the back face reflects nothing (Mitsuba's one-sided BSDFs); "
              "`back_culled`: rays pass through the back face (glTF `doubleSided: false`).",
              choices=tuple(SIDEDNESS)),
        Field("opacity", "float", 1.0, "The chance that a ray meets the surface (Mitsuba's `mask`); "
              "below 1 the rest passes through.", UNIT),
        Field("emission", "vec3", (0.0, 0.0, 0.0), "Emitted radiance, linear RGB.", NON_NEGATIVE),
        Field("emission_strength", "float", 1.0, "Multiplier folded into `emission`.",
              NON_NEGATIVE, in_model=False),
        Field("two_sided_emission", "bool", False, "Emit from both faces of the surface (pbrt's `twosided` "
              "area light), not only from the front one the normal points out of; twice the power."),
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
        Field("outside_medium", "string", "", "Name of a `[media]` entry that paths crossing the surface "
              "outwards enter (a glass sphere standing in a gas; pbrt's MediumInterface outside).",
              default_doc="the scene's: the `[fog]` medium, or none", allowed_doc="a defined medium"),
        Field("normal_map", "string", None, "An image file, relative to the scene file, read as data "
              "(not sRGB): each texel's RGB is a normal 2 rgb - 1 in the surface's frame, x along "
              "increasing texture coordinate u, y along normal x that, z along the normal (Mitsuba's "
              "`normalmap`, shadow-terminator term included). Objects without texture coordinates "
              "read texel (0, 0)'s neighbourhood.", geometries=("mesh",), default_doc="none",
              allowed_doc=", ".join(f"`{e}`" for e in MAP_IMAGE_EXTENSIONS)),
        Field("bump_map", "string", None, "An image file of heights (read as data; a colour image "
              "by its luminance): the surface's normal tilts as if displaced by `bump_scale` times the "
              "height along the normal, per unit of texture coordinate (Mitsuba's `bumpmap`).",
              geometries=("mesh",), default_doc="none",
              allowed_doc=", ".join(f"`{e}`" for e in MAP_IMAGE_EXTENSIONS)),
        Field("bump_scale", "float", 1.0, "The height of a `bump_map` texel of value 1 (negative: "
              "the map's heights are depths).", geometries=("mesh",)),
    )),
    rules=(Rule("A conductor's Fresnel comes from one description: `base_color` with `edge_tint`, or "
                "`eta` with `k`, or `metal`; fields of two of them together are an error, and `eta` and "
                "`k` come together.", check_conductor_fresnel),
           Rule("A material has at most one of `normal_map` and `bump_map`.", check_one_surface_map)),
)

_GRID = ("grid",)

MEDIUM = Section(
    "media.<name>",
    "Participating media (fog, smoke, murky liquid), one table per medium; materials "
    "(`medium`) and `[fog]` refer to them by name. Light is absorbed and scattered along the way "
    "with the Henyey-Greenstein phase function. `homogeneous`: the same coefficients everywhere. "
    "`grid`: a density on a 3D grid (Mitsuba's `.vol` format, as smoke simulations write it), "
    "extinction `scale` times the density, read trilinearly between voxel centres; the medium "
    "exists only inside the grid's box, within the surfaces whose material names it. Scenes "
    "without media compile no medium code, and scenes without a grid medium no grid code.",
    (
        Field("type", "string", "homogeneous", "Kind of medium.", choices=MEDIUM_KINDS, attr="kind"),
        Field("sigma_a", "vec3", (0.0, 0.0, 0.0), "Absorption coefficient per metre, RGB.", NON_NEGATIVE,
              only_for=("homogeneous",)),
        Field("sigma_s", "vec3", (0.1, 0.1, 0.1), "Scattering coefficient per metre, RGB.", NON_NEGATIVE,
              only_for=("homogeneous",)),
        Field("g", "float", 0.0, "Henyey-Greenstein asymmetry: 0 scatters evenly, towards 1 "
              "forwards, towards -1 backwards.", Range(-0.99, 0.99)),
        Field("file", "string", REQUIRED, "The density grid: a Mitsuba `.vol` file (float32 voxels, 1 "
              "or 3 channels, x fastest), relative to the scene file.", only_for=_GRID, in_model=False,
              default_doc="required"),
        Field("scale", "float", 1.0, "Extinction per metre of density 1: sigma_t = `scale` x density.",
              NON_NEGATIVE, only_for=_GRID),
        Field("albedo", "vec3", (0.75, 0.75, 0.75), "Single-scattering albedo sigma_s / sigma_t, RGB "
              "(where no `albedo_file` is given).", UNIT, only_for=_GRID, in_model=False),
        Field("albedo_file", "string", None, "A `.vol` grid of the albedo over the same box.",
              only_for=_GRID, in_model=False, default_doc="none"),
        Field("box_min", "vec3", None, "The grid box's lowest corner, metres (with `box_max`).",
              only_for=_GRID, in_model=False, default_doc="the file's bounding box"),
        Field("box_max", "vec3", None, "The grid box's highest corner, metres (with `box_min`).",
              only_for=_GRID, in_model=False, default_doc="the file's bounding box"),
        Field("filter", "string", "trilinear", "How the grids are read between voxel centres.",
              choices=("trilinear", "nearest"), only_for=_GRID, in_model=False),
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

_POSITIONED, _SPOT, _DIRECTIONAL = ("point", "spot", "projector"), ("spot",), ("directional",)
_PROJECTOR = ("projector",)
# Images a spot or projector may project: what the texture reader decodes (Pillow's formats, EXR).
LIGHT_IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".bmp", ".tga", ".tif", ".tiff", ".webp", ".exr")

LIGHT = Section(
    "lights",
    "Lights without a surface, one `[[lights]]` table each, as Mitsuba 3 and pbrt-v4 define them: "
    "`point` (light from one point, equal in every direction), `spot` (a point light limited to a "
    "cone, optionally projecting an image over it), `directional` (parallel light from outside the "
    "scene, like the sun) and `projector` (Mitsuba 3's: a pinhole projecting an image, like a slide "
    "projector). A field of "
    "another `type` is an error. No ray can hit them, so only light sampling finds them: the "
    "`nee` and `mis` integrators render their light; `path` (BSDF sampling alone) never sees them, "
    "as in pbrt, and `sppm` refuses a scene with them (they emit no photons yet). Intensity is radiance times "
    "area (W/sr per channel): a surface facing a point light at distance r receives the irradiance "
    "`intensity` / r^2. Scenes without such lights compile none of their code. In error messages "
    "lights are named by 0-based position, e.g. `lights[1]`.",
    (
        Field("type", "string", REQUIRED, "Kind of light.", choices=LIGHT_KINDS, attr="kind"),
        Field("position", "vec3", REQUIRED, "Where the light is, metres.", only_for=_POSITIONED,
              default_doc="required"),
        Field("direction", "dir3", REQUIRED, "`spot`: the cone's axis, the way it shines; `directional`: "
              "the way the light travels (from the light into the scene); `projector`: the way it "
              "looks. Normalised on load.", only_for=_SPOT + _DIRECTIONAL + _PROJECTOR, default_doc="required"),
        Field("up", "vec3", (0.0, 1.0, 0.0), "The projected image's up direction (as a camera's `up`); "
              "not parallel to `direction`.", only_for=_SPOT + _PROJECTOR),
        Field("intensity", "vec3", (1.0, 1.0, 1.0), "Radiant intensity, linear RGB, W/sr (a spot's, "
              "along its axis).", NON_NEGATIVE, only_for=("point", "spot")),
        Field("irradiance", "vec3", (1.0, 1.0, 1.0), "`directional`: irradiance on a surface facing the "
              "light, linear RGB, W/m^2. `projector`: multiplies its `texture` (Mitsuba's irradiance times "
              "scale): a plane facing it at distance 1 receives pi times this, so a white diffuse plane "
              "there shows it as its radiance.", NON_NEGATIVE, only_for=_DIRECTIONAL + _PROJECTOR),
        Field("cutoff_angle", "float", 20.0, "Angle from the axis beyond which the spot is dark, "
              "degrees.", Range(0.0, 180.0, lo_open=True, hi_open=True), only_for=_SPOT),
        Field("beam_width", "float", None, "Angle from the axis within which the spot has its full "
              "intensity, degrees; between it and `cutoff_angle` the intensity falls linearly in "
              "angle to 0 (Mitsuba 3's profile).", NON_NEGATIVE, only_for=_SPOT,
              default_doc="3/4 of `cutoff_angle` (Mitsuba's)"),
        Field("texture", "string", None, "An image file, relative to the scene file (8-bit images are "
              "sRGB, `.exr` linear). `spot`: projected over the cone, multiplying the intensity, the cutoff "
              "circle inscribed in the image; `projector`: the image it projects (without one, a "
              "constant `irradiance` over a square image).", only_for=_SPOT + _PROJECTOR,
              default_doc="none", allowed_doc=", ".join(f"`{e}`" for e in LIGHT_IMAGE_EXTENSIONS)),
        Field("fov", "float", 45.0, "The projector's field of view along `fov_axis`, degrees.",
              Range(0.0, 180.0, lo_open=True, hi_open=True), only_for=_PROJECTOR),
        Field("fov_axis", "string", "x", "The image axis `fov` spans: `x` (its width), `y`, `diagonal`, "
              "`smaller` or `larger` (Mitsuba's).", choices=FOV_AXES, only_for=_PROJECTOR),
    ),
    (Rule("A spot's `beam_width` is at most its `cutoff_angle`.", check_spot_beam),
     Rule("Where a spot or projector has a `texture`, its `up` is not parallel to its `direction`.",
          check_light_up)),
    heading="`[[lights]]`",
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
                   check_rounded_box),)),
    NodeKind("torus", "A ring in the xz plane, centred at the origin.",
             (_length("major_radius", 0.5, "Distance from the centre to the tube's centre line."),
              _length("minor_radius", 0.15, "Tube radius.")),
             (Rule("`minor_radius` must be smaller than `major_radius`.", check_torus),)),
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
MESH_FILE_EXTENSIONS = (".gltf", ".glb", ".obj", ".ply", ".stl", ".serialized")

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
             (Field("file", "string", REQUIRED, "Model file, `.gltf`, `.glb`, `.obj`, `.ply`, "
                    "`.stl` or Mitsuba's `.serialized` (every shape it holds). A relative path is relative to the scene file's folder.",
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
                         "no segment that is a single point or lies on the axis.", check_profile),)),
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

# The fields of a water surface's random wave set (excluded by `waves`).
WATER_RANDOM_SET = (
    Field("wave_count", "int", 4, "Random set: how many waves.", Range(1, 64)),
    Field("wavelength", "float", 1.0, "Random set: the longest wavelength, metres; the others are "
          "log-uniform down to a quarter of it.", POSITIVE),
    Field("amplitude", "float", 0.02, "Random set: the amplitude of a wave `wavelength` long, metres; "
          "shorter waves are proportionally lower (equally steep).", NON_NEGATIVE),
    Field("direction", "float", 0.0, "Random set: mean direction of travel, degrees from +x towards +z."),
    Field("spread", "float", 30.0, "Random set: directions are uniform within `direction` +- `spread`, "
          "degrees.", Range(0.0, 180.0)),
    Field("steepness", "float", 0.5, "Random set: the Gerstner steepness of every wave.", UNIT),
    Field("seed", "int", 0, "Random set: the seed; the same seed gives the same waves.", NON_NEGATIVE),
)

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
               *WATER_RANDOM_SET),
              (Rule("`waves` and the random-set fields (`wave_count`, `wavelength`, `amplitude`, "
                    "`direction`, `spread`, `steepness`, `seed`) exclude each other.",
                    water_fields_check(WATER_RANDOM_SET)),
               Rule("Every wavelength spans at least two grid cells (2 * `size` / `resolution`), and "
                    "the sum over the waves of steepness * 2 pi * amplitude / wavelength stays below 1 "
                    "(else Gerstner crests loop and the surface intersects itself).", check_water_waves))),
    Generator("cylinder", "An open tube (no caps) about the local y axis from y = 0 to y = `height`: "
              "`sectors` quads around (2 triangles each) with the exact surface's normals at their "
              "vertices, facing outwards, and texture coordinates u = the angle from +x towards -z "
              "over 360 degrees, v = y / `height` (Mitsuba's cylinder's).",
              (Field("radius", "float", 1.0, "Radius, metres.", POSITIVE),
               Field("height", "float", 1.0, "Length along y, metres.", POSITIVE),
               Field("sectors", "int", 256, "Quads around; the silhouette lies within about "
                     "5 radius / sectors^2 of the true one.", Range(3, 65536)))),
    Generator("disc_fan", "A disc in the local xz plane facing +y, centred at the origin, as `sectors` "
              "thin triangles from the centre, with texture coordinates u = the distance from the "
              "centre / `radius`, v = the angle from +x towards -z over 360 degrees (Mitsuba's disk's). "
              "Unlike the analytic `disc` it takes any transform (an ellipse) and carries texture "
              "coordinates.",
              (Field("radius", "float", 1.0, "Radius, metres.", POSITIVE),
               Field("sectors", "int", 1024, "Triangles around.", Range(3, 65536)))),
    Generator("cube", "A cube centred at the origin, 2 triangles a face with face normals, each face's "
              "texture coordinates spanning [0, 1] x [0, 1] as Mitsuba's cube lays them out.",
              (Field("size", "float", 2.0, "Edge length, metres.", POSITIVE),)),
)

GENERATORS_BY_NAME = {g.name: g for g in GENERATORS}

# Top-level sections, in the order the documentation presents them.
TOP_LEVEL = ("scene", "camera", "render", "environment", "lights", "materials", "model_materials", "media", "fog",
             "objects")
SECTIONS = (SCENE, CAMERA, RENDER, MARCH, ENVIRONMENT, LIGHT, MATERIAL, MODEL_MATERIAL, MEDIUM, FOG)

ENV_MAP_EXTENSIONS = (".exr", ".hdr")
SCENE_EXTENSIONS = (".toml",)

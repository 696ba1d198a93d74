"""Plain-data description of a scene, as the loaders produce it and the renderer consumes it.

Everything here is numpy or frozen dataclasses: no Taichi, so loading and validation are testable
without kernels. Units are metres; angles are stored in degrees exactly as written in scene files
and converted to radians where they are used.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

from renderer.materials.kinds import KIND_NAMES, SHARED_ROUGHNESS, default_on
from renderer.scene.model_files import ModelFiles

Vec3 = tuple[float, float, float]

# Kinds known to the renderer. The loader refuses anything else with a one-line error. Material
# kinds are the registry's (renderer/materials/kinds.py).
MATERIAL_KINDS = KIND_NAMES
FOG_MODELS = ("none", "medium", "analytic")
SDF_PRIMITIVES = ("sphere", "box", "rounded_box", "torus", "capsule", "cylinder", "cone", "plane")
SDF_OPERATORS = ("union", "intersection", "subtraction", "smooth_union", "repeat")
ENVIRONMENT_KINDS = ("map", "sky", "constant")
GEOMETRY_KINDS = ("sdf", "mesh")
MESH_OBJECT_KINDS = ("mesh", "sphere", "quad", "disc", "generated", "bezier")
MESH_GENERATORS = ("terrain", "icosphere", "light_panels", "water", "cylinder", "disc_fan", "cube")
LIGHT_KINDS = ("point", "spot", "directional", "projector")
FOV_AXES = ("x", "y", "diagonal", "smaller", "larger")  # what a projector's fov spans (Mitsuba's)
PROJECTIONS = ("perspective", "orthographic")
MESH_NORMALS = ("file", "flat", "smooth")


@dataclass(frozen=True)
class CameraSpec:
    position: Vec3 = (0.0, 1.0, 5.0)
    look_at: Vec3 = (0.0, 0.0, 0.0)
    up: Vec3 = (0.0, 1.0, 0.0)
    fov: float = 45.0  # vertical field of view, degrees
    aperture: float = 0.0  # lens radius in metres; 0 is a pinhole
    focus_distance: float = 5.0  # metres along the view direction
    projection: str = "perspective"  # one of PROJECTIONS
    ortho_height: float = 2.0  # orthographic: the height of the view, metres (its width follows the image's)
    # A camera path (renderer/commands/animation/camera_path.py): per keyframe its fields as sorted (name,
    # value) pairs, as the loader reads tables of known fields (time, position, look_at; fov and up
    # None where the camera's apply). Empty: the camera stands still.
    keyframes: tuple[tuple[tuple[str, object], ...], ...] = ()


@dataclass(frozen=True)
class MarchSettings:
    """Sphere-tracing knobs (SDF scenes only)."""

    hit_threshold: float = 1.0  # hit when distance < hit_threshold * pixel footprint at that range
    min_threshold: float = 1e-4  # absolute floor on the hit distance, metres
    max_steps: int = 256
    max_distance: float = 100.0  # metres
    over_relaxation: float = 3.0  # the longest step in distance bounds; 1.0 is plain sphere tracing
    adaptive: bool = True  # step length from the distance's slope along the ray, up to over_relaxation


@dataclass(frozen=True)
class RenderSettings:
    width: int = 640
    height: int = 360
    spp: int = 64
    max_depth: int = 8  # Mitsuba convention: 1 = emitters seen directly, 2 = direct light, ...
    integrator: str = "mis"
    seed: int = 0
    march: MarchSettings = field(default_factory=MarchSettings)
    sampler: str = "independent"  # "independent" | "sobol"
    energy_compensation: bool = True  # Kulla-Conty multiple scattering for rough GGX metals
    # How textures are read over a pixel's footprint: "anisotropic" | "trilinear" mip-mapping, or
    # "none" (the image itself; renderer/materials/texture_sampler.py)
    texture_filter: str = "anisotropic"
    pixel_filter: str = "box"  # "box" | "tent" | "gaussian" (renderer/film/pixel_filter.py)
    filter_radius: float = 1.0  # tent, pixels
    filter_stddev: float = 0.5  # gaussian, pixels (cut off at four deviations)
    # The window of the width x height image that is rendered and written, (x, y, width, height) in
    # pixels from its top-left corner (Mitsuba's hdrfilm crop): the projection stays the whole
    # image's (renderer/film/crop_window.py). None: the whole image.
    crop: Optional[tuple[int, int, int, int]] = None
    exposure: float = 0.0  # EV: display values are radiance times 2^exposure (PNG, the viewer); EXR keeps radiance

    @property
    def image_size(self) -> tuple[int, int]:
        """The size of the image rendered and written: the crop window's, else width x height."""
        return (self.crop[2], self.crop[3]) if self.crop is not None else (self.width, self.height)


@dataclass(frozen=True)
class EnvironmentSpec:
    kind: str = "sky"  # "map" | "sky" | "constant"
    file: Optional[Path] = None  # resolved absolute path, for kind == "map"
    intensity: float = 1.0
    rotation: float = 0.0  # degrees about rotation_axis, right-handed (Mitsuba's to_world rotate(axis, angle))
    rotation_axis: Vec3 = (0.0, 1.0, 0.0)  # +y: a turn in azimuth, the kernels' cheap case
    color: Vec3 = (1.0, 1.0, 1.0)  # kind == "constant"
    zenith: Vec3 = (0.25, 0.45, 0.9)  # kind == "sky"
    horizon: Vec3 = (0.9, 0.9, 1.0)
    ground: Vec3 = (0.3, 0.28, 0.25)
    # Any orientation, from a format that gives one as a matrix (a Mitsuba `to_world`): 3 rows of 3,
    # orthogonal (a rotation, or one with a mirror), from the environment's own frame (where the map
    # convention holds) to the world's. When given it replaces rotation and rotation_axis.
    to_world: Optional[tuple[tuple[float, float, float], ...]] = None

    def rotation_matrix(self) -> np.ndarray:
        """The 3x3 matrix (float64) from the environment's own frame to the world's."""
        if self.to_world is not None:
            return np.array(self.to_world, np.float64)
        axis = np.asarray(self.rotation_axis, np.float64)
        x, y, z = axis / np.linalg.norm(axis)
        k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
        angle = np.radians(self.rotation)
        return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)  # Rodrigues, right-handed

    def y_rotation(self) -> Optional[float]:
        """The orientation as degrees about +y where it is a turn about +y (or none), which the
        kernels apply as an azimuth offset; None where it takes a full 3x3 matrix."""
        if self.to_world is None:
            x, y, z = self.rotation_axis
            if x == 0.0 and z == 0.0:
                return self.rotation if y > 0.0 else -self.rotation
            return 0.0 if self.rotation % 360.0 == 0.0 else None
        m = self.rotation_matrix()
        angle = np.arctan2(m[0, 2], m[0, 0])
        c, s = np.cos(angle), np.sin(angle)
        about_y = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        return float(np.degrees(angle)) if np.allclose(m, about_y, rtol=0.0, atol=1e-6) else None

    @property
    def needs_matrix(self) -> bool:
        """Whether its kernels turn directions by the full matrix (Features.environment_rotated): a
        map or sky oriented otherwise than about +y; a constant colour looks the same every way."""
        return self.kind != "constant" and self.y_rotation() is None


IDENTITY_UV = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
TEXTURE_KINDS = ("bitmap", "checkerboard", "mix", "product")


@dataclass(frozen=True)
class TextureSpec:
    """An image on a material parameter, from a scene format that puts one there (a Mitsuba
    `bitmap` or `checkerboard`); the image is read when the scene is assembled
    (renderer/scene/texture_images.py). Its value multiplies the parameter's."""

    kind: str  # one of TEXTURE_KINDS
    file: Optional[Path] = None  # bitmap: the image file
    srgb: bool = True  # bitmap: colours stored sRGB-encoded (decoded to linear); False: as stored
    wrap: str = "repeat"  # "repeat" | "clamp" | "mirror", both directions
    nearest: bool = False  # the nearest texel instead of bilinear filtering
    transform: tuple[tuple[float, float, float], ...] = IDENTITY_UV  # uv' = transform @ (u, v, 1)
    color0: Vec3 = (0.4, 0.4, 0.4)  # checkerboard: where frac(u') and frac(v') fall on the same side of 1/2
    color1: Vec3 = (0.2, 0.2, 0.2)  # checkerboard: elsewhere
    # mix and product (pbrt's `mix` and `scale` of two textures): two operands, each a colour times
    # a texture or None; mix: (1 - amount) * first + amount * second, the amount a number times the
    # first channel of a texture or None; product: first * second. Baked into one image when the
    # scene is assembled (renderer/scene/texture_mixing.py), read with this spec's transform, wrap
    # and filter, which are its operands' own.
    operands: tuple = ()
    amount: tuple = (0.5, None)

    @staticmethod
    def constant(value: float) -> "TextureSpec":
        """One value everywhere (a textured lobe's other, untextured width)."""
        return TextureSpec("checkerboard", color0=(value,) * 3, color1=(value,) * 3, nearest=True)


@dataclass(frozen=True)
class MeshAttributeColor:
    """A colour read, per vertex or per face, from an attribute a mesh file carries (Mitsuba's
    `mesh_attribute` texture on a PLY mesh): offset + scale * the attribute's value (a
    one-channel attribute is grey). `name` is Mitsuba's: vertex_<prefix> or face_<prefix> for the
    PLY properties <prefix>_0, <prefix>_1, ... (vertex_color also for red, green, blue)."""

    name: str
    offset: Vec3 = (0.0, 0.0, 0.0)
    scale: Vec3 = (1.0, 1.0, 1.0)


@dataclass(frozen=True)
class MaterialSpec:
    name: str
    kind: str = "diffuse"  # one of MATERIAL_KINDS
    base_color: Vec3 = (0.8, 0.8, 0.8)  # albedo (diffuse), F0 (conductor), transmittance tint (dielectric)
    # Perceptual roughness in [0, 1]; alpha = roughness^2; 0 is a perfect mirror. None: the kind's
    # default (renderer/materials/kinds.py: 0 for conductors and dielectrics, else 0.5).
    roughness: Optional[float] = None
    ior: float = 1.5  # dielectric index of refraction
    emission: Vec3 = (0.0, 0.0, 0.0)  # emitted radiance, linear RGB (colour times strength)
    edge_tint: Vec3 = (1.0, 1.0, 1.0)  # conductor only: tint at grazing angles (Hoffman's F82 model)
    metallic: float = 0.0  # principled only: 0 dielectric base, 1 metal (glTF metallic)
    transmission: float = 0.0  # principled only: fraction of the dielectric base that transmits
    medium: str = ""  # the participating medium inside surfaces of this material ("" = none)
    # the medium a path crossing out of such a surface enters ("" = the scene's: the fog's medium, or
    # none); pbrt's MediumInterface outside, e.g. a glass sphere standing in a gas
    outside_medium: str = ""
    two_sided_emission: bool = False  # an emitter shines from both faces (pbrt's twosided area light)
    transmittance: Vec3 = (0.2, 0.2, 0.2)  # diffuse_transmission: Lambert transmission's colour (with base_color, <= 1)
    abbe: float = 0.0  # dielectric dispersion: Abbe number of a Cauchy curve through ior (0 = none)
    glass: str = ""  # dielectric dispersion: a real glass's Sellmeier curve (overrides ior and abbe)
    eta: Optional[Vec3] = None  # conductor only: real part of the complex index (RGB), with k
    k: Optional[Vec3] = None  # conductor only: imaginary part (extinction), with eta
    metal: str = ""  # conductor only: a named measured metal (its eta and k), e.g. "Au"
    thin: bool = False  # dielectric / principled: a thin-walled shell, transmission passes straight through
    clearcoat: float = 0.0  # principled layers (glTF clearcoat, sheen, specular extensions)
    clearcoat_roughness: float = 0.0
    sheen_color: Vec3 = (0.0, 0.0, 0.0)
    sheen_roughness: float = 0.0
    specular: float = 1.0
    specular_color: Vec3 = (1.0, 1.0, 1.0)
    base_color_texture: Optional[TextureSpec] = None  # multiplies base_color where given
    # The microfacet model of rough conductors, dielectrics and plastics: "ggx" (height-correlated
    # masking), "ggx_separable" or "beckmann" (separable masking, Mitsuba 3's); see
    # renderer/materials/microfacet.py.
    microfacet: str = "ggx"
    # Anisotropic roughness: the perceptual roughness along the surface's dp/dv, `roughness` being
    # along dp/du (Mitsuba's alpha_u and alpha_v as square roots); None: isotropic.
    roughness_v: Optional[float] = None
    # Microfacet widths alpha (= roughness^2) from textures' first channel, in place of roughness
    # and roughness_v (Mitsuba's textured alpha, alpha_u, alpha_v).
    alpha_texture: Optional[TextureSpec] = None
    alpha_v_texture: Optional[TextureSpec] = None
    nonlinear: bool = False  # plastic: Mitsuba's `nonlinear` (the base's colour deepens under the coat)
    # coated (pbrt-v4's coateddiffuse / coatedconductor): the base ("diffuse": base_color;
    # "conductor": eta and k, or metal, default copper), the slab's thickness, its medium's albedo
    # and HG g, the random walks' depth and count, the conductor's perceptual roughness.
    coat_base: str = "diffuse"
    coat_thickness: float = 0.01
    coat_albedo: Vec3 = (0.0, 0.0, 0.0)
    coat_g: float = 0.0
    coat_maxdepth: int = 10
    coat_nsamples: int = 1
    conductor_roughness: float = 0.0
    sidedness: str = "two_sided"  # "two_sided", "back_black" (Mitsuba's one-sided BSDFs) or "back_culled"
    # Coverage (Mitsuba's mask BSDF): the surface is there with probability opacity (times the
    # opacity texture's first channel where given); 1 is opaque.
    opacity: float = 1.0
    opacity_texture: Optional[TextureSpec] = None
    emission_texture: Optional[TextureSpec] = None  # multiplies emission where given (a textured area light)
    # Multiplies base_color per vertex or face of each mesh drawn with this material (which must
    # carry the attribute); the mesh's own vertex colours are replaced.
    base_color_attribute: Optional[MeshAttributeColor] = None
    # Mitsuba's normalmap: a raw RGB normal, 2 rgb - 1, in the surface's shading frame (its tangent
    # along dp/du); bumpmap: a height field whose texture-space gradient, times bump_scale, tilts
    # the shading normal (renderer/materials/mapped_frames.py). At most one of the two.
    normal_map: Optional[TextureSpec] = None
    bump_map: Optional[TextureSpec] = None
    bump_scale: float = 1.0
    # Disney's principled BSDF as Mitsuba 3 defines it (kind "disney", renderer/materials/disney.py):
    # the weights of its lobes and tints, each in [0, 1] (diff_trans in [0, 2]); metallic,
    # transmission (Disney's spec_trans), clearcoat, ior and thin are the fields above.
    anisotropic: float = 0.0
    sheen: float = 0.0
    sheen_tint: float = 0.0
    spec_tint: float = 0.0
    clearcoat_gloss: float = 0.0
    flatness: float = 0.0
    diff_trans: float = 0.0
    # Disney: the back face shades as the front (Mitsuba's twosided around a principled); else
    # the back is the inside of the model, black unless it transmits.
    front_both_sides: bool = False
    # Textures on scalar parameters, (parameter, texture) pairs: the texture's first channel
    # multiplies the parameter (DISNEY_TEXTURED names those that take one).
    parameter_textures: tuple = ()
    # A mix (Mitsuba's blendbsdf, pbrt's mix): at each shading point the second of the two
    # materials with probability mix_weight (times the "mix_weight" texture's first channel, as a
    # parameter texture), else the first; the mix keeps its own emission, medium, coverage and
    # normal or bump map. kind then only names the first's.
    mix: Optional[tuple] = None
    mix_weight: float = 0.5

    def __post_init__(self):
        if self.roughness is None:
            object.__setattr__(self, "roughness", default_on(self.kind, "roughness", SHARED_ROUGHNESS))

    @property
    def textures(self) -> dict[str, "TextureSpec"]:
        """The material's textures by role ("base_color", "opacity", "emission", "normal", "bump",
        "alpha", "alpha_v", the parameters of parameter_textures, and a mix's materials' roles
        prefixed "mix0." and "mix1."), those it has."""
        roles = {"base_color": self.base_color_texture, "opacity": self.opacity_texture,
                 "emission": self.emission_texture, "normal": self.normal_map, "bump": self.bump_map,
                 "alpha": self.alpha_texture, "alpha_v": self.alpha_v_texture, **dict(self.parameter_textures)}
        for i, part in enumerate(self.mix or ()):  # the mixed materials' own, by a prefixed role
            roles.update({f"mix{i}.{role}": texture for role, texture in part.textures.items()})
        return {role: texture for role, texture in roles.items() if texture is not None}

    @property
    def is_dispersive(self) -> bool:
        return self.kind == "dielectric" and (self.abbe > 0.0 or bool(self.glass))

    @property
    def has_complex_ior(self) -> bool:
        """A conductor whose Fresnel comes from eta + i k (written, or a named metal's)."""
        return self.kind == "conductor" and (bool(self.metal) or self.eta is not None)

    @property
    def is_emissive(self) -> bool:
        return max(self.emission) > 0.0


MEDIUM_KINDS = ("homogeneous", "grid")
IDENTITY_4X4 = tuple(tuple(float(r == c) for c in range(4)) for r in range(4))


@dataclass(frozen=True)
class VolumeGridSpec:
    """A quantity on a 3D grid (Mitsuba's gridvolume; a constant is a 1x1x1 grid): the grid fills
    the unit cube [0, 1]^3 that `to_world` places in the scene, its voxel values at the cell
    centres, read trilinearly (or from the nearest voxel) and clamped at the faces."""
    values: np.ndarray = field(compare=False, repr=False)  # (zres, yres, xres, channels) f32, 1 or 3 channels
    to_world: tuple[tuple[float, ...], ...] = IDENTITY_4X4
    nearest: bool = False
    file: Optional[Path] = None  # the .vol file the values came from (renderer/scene/vol_files.py)
    constant: Optional[Vec3] = None  # or the constant they are (what compares, with the fields above)


@dataclass(frozen=True)
class MediumSpec:
    """A participating medium and its Henyey-Greenstein asymmetry g (0 isotropic, > 0 forward).
    kind "homogeneous": coefficients per metre, RGB. kind "grid" (Mitsuba's heterogeneous medium):
    extinction sigma_t(x) = scale * density(x) and single-scattering albedo(x) from grids, the
    medium only inside the density grid's box; its sigma_a and sigma_s are zero."""
    name: str
    sigma_a: Vec3 = (0.0, 0.0, 0.0)
    sigma_s: Vec3 = (0.1, 0.1, 0.1)
    g: float = 0.0
    kind: str = "homogeneous"  # one of MEDIUM_KINDS
    density: Optional[VolumeGridSpec] = None
    albedo: Optional[VolumeGridSpec] = None
    scale: float = 1.0

    def __post_init__(self):
        if self.kind == "grid":  # its homogeneous row must add nothing to the grid's tracking
            object.__setattr__(self, "sigma_a", (0.0, 0.0, 0.0))
            object.__setattr__(self, "sigma_s", (0.0, 0.0, 0.0))


@dataclass(frozen=True)
class FogSpec:
    """What fills the space between objects: nothing, a medium (physical fog), or the analytic
    exponential blend (a named approximation applied to camera rays)."""
    model: str = "none"  # one of FOG_MODELS
    medium: str = ""  # model "medium": the name of a [media] entry
    density: float = 0.1  # model "analytic": extinction per metre
    color: Vec3 = (0.7, 0.75, 0.8)  # model "analytic": the colour distance fades to


@dataclass(frozen=True)
class LightSpec:
    """A light with no surface (Mitsuba 3's and pbrt-v4's point, spot and directional; Mitsuba's
    projector): a delta in position or direction, so no ray can hit it; only light sampling (nee, mis) finds it.

    point: `position`, radiant `intensity` (W/sr per channel, i.e. radiance times m^2): the
    irradiance at distance r facing it is intensity / r^2.
    spot: a point light limited to a cone about `direction`: full intensity within `beam_width`
    degrees of the axis, falling linearly in angle to 0 at `cutoff_angle` (Mitsuba 3's profile);
    None: 3/4 of the cutoff, as in Mitsuba.
    directional: parallel light travelling along `direction` from outside the scene, `irradiance`
    (W/m^2 per channel) on a surface facing it.
    projector: Mitsuba 3's projector, a pinhole at `position` looking along `direction` (image
    up towards `up`) that projects `texture` times `irradiance` (a constant colour without a
    texture) through a field of view of `fov` degrees along `fov_axis`; a plane at
    distance 1 facing it receives pi times that irradiance.
    A spot's `texture` is an image projected over its cone (Mitsuba's: the cone's cutoff circle is
    inscribed in the image), multiplying its intensity; `up` orients it.
    """

    kind: str  # one of LIGHT_KINDS
    position: Vec3 = (0.0, 0.0, 0.0)  # point, spot, projector
    direction: Vec3 = (0.0, 0.0, 1.0)  # spot, projector: the axis; directional: where the light travels (unit)
    intensity: Vec3 = (1.0, 1.0, 1.0)  # point, spot
    irradiance: Vec3 = (1.0, 1.0, 1.0)  # directional, projector
    cutoff_angle: float = 20.0  # spot, degrees from the axis
    beam_width: Optional[float] = None  # spot, degrees; None: 3/4 of cutoff_angle
    up: Vec3 = (0.0, 1.0, 0.0)  # spot, projector: the image's up direction (not parallel to direction)
    texture: Optional[TextureSpec] = None  # spot: projected over the cone; projector: the image
    fov: float = 45.0  # projector: field of view in degrees along fov_axis
    fov_axis: str = "x"  # projector: x (the image's width), y, diagonal, smaller or larger

    @property
    def beam(self) -> float:
        """The spot's beam width in degrees, the default resolved."""
        return 0.75 * self.cutoff_angle if self.beam_width is None else self.beam_width


@dataclass(frozen=True)
class Transform:
    translate: Vec3 = (0.0, 0.0, 0.0)
    rotate: Vec3 = (0.0, 0.0, 0.0)  # Euler degrees, applied about x, then y, then z (R = Rz Ry Rx)
    scale: float = 1.0  # uniform only: a non-uniform scale would break the distance bound

    @property
    def is_identity(self) -> bool:
        return self.translate == (0.0, 0.0, 0.0) and self.rotate == (0.0, 0.0, 0.0) and self.scale == 1.0

    def rotation_matrix(self) -> np.ndarray:
        rx, ry, rz = np.radians(self.rotate)
        cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
        mx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
        my = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        mz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
        return mz @ my @ mx


@dataclass(frozen=True)
class SdfNode:
    """One node of an SDF tree: a primitive (leaf) or an operator over children.

    `params` holds the kind's numeric parameters with defaults filled in, e.g. sphere {"radius": r},
    box {"size": (x, y, z)}, smooth_union {"k": k}, repeat {"period": (x, y, z), "limit": (...) or None}.
    `material` is set on top-level objects only; children inherit their top-level object's material.
    """

    kind: str
    params: tuple[tuple[str, object], ...] = ()
    children: tuple["SdfNode", ...] = ()
    transform: Transform = field(default_factory=Transform)
    material: Optional[str] = None

    def param(self, name: str):
        return dict(self.params)[name]

    @property
    def is_primitive(self) -> bool:
        return self.kind in SDF_PRIMITIVES

    def walk(self):
        yield self
        for child in self.children:
            yield from child.walk()


@dataclass(frozen=True)
class MeshObject:
    """One object of a mesh scene.

    kind "mesh": a model file (glTF/GLB, OBJ, PLY); its own materials unless `material` overrides.
    kind "sphere": radius; "disc": radius, in the local xz plane facing +y; "quad": size (x, z),
    centred in the local xz plane facing +y; "generated": a procedural mesh (`generator` and its
    `params`, e.g. terrain {"resolution", "size", "height", "seed"}, icosphere {"subdivisions",
    "radius"}); "bezier": a surface of revolution about the local y axis of a profile of Bezier
    segments of `degree` (1 to 3) with control points `profile` ((radius, height) pairs, segments
    sharing end points), split into `spans` patches per segment along it and `sectors` around.
    Analytic, Bezier and generated objects need `material`.
    The transform applies scale, then rotation (Euler degrees, x then y then z), then translation.
    Spheres and discs need a uniform scale (an ellipse is not a disc).
    """

    kind: str
    file: Optional[Path] = None
    material: Optional[str] = None
    radius: float = 0.5
    size: tuple[float, float] = (1.0, 1.0)
    generator: Optional[str] = None
    params: tuple[tuple[str, object], ...] = ()
    profile: tuple[tuple[float, float], ...] = ()
    degree: int = 3
    spans: int = 4
    sectors: int = 16
    translate: Vec3 = (0.0, 0.0, 0.0)
    rotate: Vec3 = (0.0, 0.0, 0.0)
    scale: Vec3 = (1.0, 1.0, 1.0)
    # Any affine object-to-world matrix (4 rows of 4), from a format that places objects so (a
    # Mitsuba `to_world`); when given it replaces translate, rotate and scale.
    to_world: Optional[tuple[tuple[float, ...], ...]] = None
    # How a triangle mesh (kinds mesh and generated) is taken from its source, for formats that say
    # so (renderer/scene/mesh_adjustments.py): `normals` one of MESH_NORMALS ("file": the vertex
    # normals it has, flat where it has none; "flat": face normals; "smooth": the file's, else
    # vertex normals weighted by the faces' angles); `flip_normals` turns its front side over
    # (winding and normals; on a sphere, quad or disc its normal: a sphere's points inwards);
    # `flip_v` takes v to 1 - v; `part` draws only the file's meshes of
    # that name (a Mitsuba serialized file's shape k is "shape k"); `vertex_colors` False drops the
    # file's vertex colours (Mitsuba's meshes shade with them only through a mesh_attribute texture).
    normals: str = "file"
    flip_normals: bool = False
    flip_v: bool = False
    part: Optional[str] = None
    vertex_colors: bool = True
    # A model file that does not read (malformed, nothing drawable) is left out with one warning
    # instead of stopping the scene: set by readers of formats whose scenes name many mesh files
    # (pbrt-v4), where one bad file should not refuse the rest.
    skip_unreadable: bool = False

    def matrix(self) -> np.ndarray:
        """The 4x4 object-to-world matrix."""
        if self.to_world is not None:
            return np.array(self.to_world, np.float64)
        m = np.eye(4)
        m[:3, :3] = Transform(rotate=self.rotate).rotation_matrix() @ np.diag(self.scale)
        m[:3, 3] = self.translate
        return m

    def centre_and_scale(self) -> tuple[tuple[float, float, float], float]:
        """Where an analytic sphere or disc sits, and its (uniform) scale."""
        if self.to_world is None:
            return self.translate, self.scale[0]
        m = self.matrix()
        return tuple(float(x) for x in m[:3, 3]), float(np.linalg.norm(m[:3, 0]))


@dataclass(frozen=True)
class Scene:
    name: str
    path: Optional[Path]  # the file it came from, for error messages
    geometry: str  # one of GEOMETRY_KINDS
    camera: CameraSpec
    render: RenderSettings
    environment: EnvironmentSpec
    materials: tuple[MaterialSpec, ...]
    sdf_objects: tuple[SdfNode, ...] = ()
    description: str = ""
    mesh_objects: tuple[MeshObject, ...] = ()
    media: tuple[MediumSpec, ...] = ()
    fog: FogSpec = field(default_factory=FogSpec)
    lights: tuple[LightSpec, ...] = ()  # point, spot and directional lights
    # The model files the scene reads, each parsed once (shared by camera framing and assembly).
    model_files: ModelFiles = field(default_factory=ModelFiles, compare=False, repr=False)
    # Files the reader read besides `path` (a Mitsuba scene's includes and spectrum files): with the
    # model files and textures they are what a checkpoint's fingerprint and a distributed bundle cover.
    source_files: tuple[Path, ...] = ()
    # The parameters a reader substituted from the command line (a Mitsuba scene's -D NAME=VALUE): the
    # same files with other parameters are another scene, to a checkpoint's fingerprint too.
    parameters: tuple[tuple[str, str], ...] = ()
    # Edits of model files' own materials ([model_materials.<i>]): (i, ((PbrMaterial attribute, value),
    # ...)) per edited material, i counting the model materials in the order the objects read them.
    model_material_edits: tuple = ()
    # A scene read from a TOML scene of edits (renderer/scene/edits_file.py): the scene of the file
    # it edits, as that file gives it; saving edits again writes what differs from it.
    edited_from: Optional["Scene"] = field(default=None, compare=False, repr=False)

    def medium_names(self) -> tuple[str, ...]:
        return tuple(m.name for m in self.media)

    def material_index(self, name: str) -> int:
        for i, m in enumerate(self.materials):
            if m.name == name:
                return i
        raise KeyError(name)

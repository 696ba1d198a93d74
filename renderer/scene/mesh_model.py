"""Plain-data triangle meshes, PBR materials and textures, as `renderer.scene.model_formats` produces them.

Everything is numpy and dataclasses (no Taichi): the renderer uploads these arrays, the BVH builder
reads `positions` and `indices`, and the texture atlas (`renderer.scene.textures`) packs `images`.

Conventions (shared by every loader, whatever the file format stores):

- `MeshAsset.meshes` are in WORLD space, metres: node transforms are already applied. Those are
  the meshes a file places once. A glTF mesh placed by two or more nodes, or by a node with
  EXT_mesh_gpu_instancing, is stored once in `MeshAsset.instanced` instead (see "Instances").
  A world mesh's triangles are counter-clockwise seen from its front side, also under mirroring
  node transforms (the loader reverses the winding when det(M) < 0).
- Normals are unit length, transformed with the cofactor matrix of the node matrix (det(M) times
  its inverse transpose: the same directions, and defined for a flattening M). `None` means the
  file had none: shade with the geometric normal (glTF prescribes flat shading then).
- UV sets follow glTF: u to the right, v DOWN, (0, 0) is the top-left corner of the image and
  image row 0 is the top row. OBJ, PLY and other v-up formats are flipped at load (v -> 1 - v).
  The KHR_texture_transform matrix of a `TextureRef` is NOT applied to the stored UVs: the sampler
  applies it per texture slot, `uv' = (ref.matrix @ [u, v, 1])[:2]`.
- Tangents are (xyz, w): a unit tangent along increasing u, orthogonal to the normal, and the
  handedness w = +-1. The bitangent is `B = w * cross(N, T)`; it points "up" in the image
  (towards decreasing stored v), which is the +y of a glTF/MikkTSpace tangent-space normal map.
  A shading normal is `normalize(T * n.x + B * n.y + N * n.z)` with
  `n = (2 * texel.rgb - 1) * (normal_scale, normal_scale, 1)`.
- Images (`MeshAsset.images`, `TextureImage`) keep the file's precision and encoding: 8-bit
  files stay uint8 RGBA, 16-bit ones become float16 (k / 65535), float ones float32. Grey is
  replicated to RGB and a missing alpha is opaque. Each entry says how a lookup decodes it:
  `srgb` entries (the colour slots glTF defines as sRGB: base colour, emissive, sheen colour,
  specular colour) turn RGB from sRGB to linear PER TEXEL, before filtering; alpha and the data
  slots (metallic-roughness, normal, transmission, clearcoat, ...) are read as stored. An image
  used both as colour and as data is two entries sharing one pixel array, stored once.
  `TextureImage.linear()` is the decoded image, the values every lookup must agree with.
- Base colour alpha is the alpha channel of the base colour texture times `base_color_factor[3]`,
  times the vertex colour's alpha. `alpha_mode` / `alpha_cutoff` say how to use it (glTF).
  OBJ `d` < 1 on a non-glass illum model becomes alpha BLEND.
- Vertex colours (`TriangleMesh.colors`) are LINEAR RGBA: glTF COLOR_0 is linear (normalized
  8/16-bit integers are k / 255 or k / 65535); PLY colours are sRGB in the file and decoded at load.
- Occlusion textures are ignored on purpose: a path tracer computes occlusion itself, and
  multiplying a baked ambient-occlusion map on top would darken the image twice.

Instances
---------
`InstancedMesh` is one glTF primitive stored ONCE in its mesh's local frame (validated and
cleaned like a world mesh, with winding, normals and tangents as in the file) and a float64
(N, 4, 4) array `matrices` of object-to-world transforms, one per placement (node world matrix,
times the per-instance TRS of EXT_mesh_gpu_instancing when the node has one). For instance k,
with M = matrices[k] acting on column vectors (p_world = M @ [p, 1]):
  - positions: M[:3, :3] @ p + M[:3, 3];
  - normals: cofactor(M[:3, :3]) @ n, normalised (cofactor = det * inverse transpose, so a zero
    scale still gives the flattened plane's normal); the geometric normal cross(b - a, c - a)
    transforms the same way;
  - tangents: M[:3, :3] @ t.xyz, normalised (still orthogonal to the normal); w times sign(det M);
  - mirrored instances (det M < 0): the stored winding is then clockwise seen from the front,
    i.e. the front side flips; a consumer reverses the winding (or flips the side it reports).
`place_mesh` does exactly this and returns a world-space `TriangleMesh` (`InstancedMesh.placed(k)`
for instance k); mesh_assembly places scene objects with it too.
Every matrix is finite; `MeshAsset.bounds` include every instance.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

from renderer.scene.srgb import SRGB8_TO_LINEAR, srgb_to_linear

WRAP_MODES = ("repeat", "clamp", "mirror")
ALPHA_MODES = ("OPAQUE", "MASK", "BLEND")

IDENTITY_UV_TRANSFORM: tuple[tuple[float, float, float], ...] = (
    (1.0, 0.0, 0.0),
    (0.0, 1.0, 0.0),
    (0.0, 0.0, 1.0),
)


def uv_transform_matrix(offset=(0.0, 0.0), rotation: float = 0.0, scale=(1.0, 1.0)) -> np.ndarray:
    """The KHR_texture_transform matrix `T @ R @ S` (row-major, acting on column vectors (u, v, 1)).

    `rotation` is in radians, counter-clockwise in the glTF UV frame (v down), as the extension's
    reference implementations and its "lower-left quadrant rotated 90 degrees" example agree:
    R = [[cos, sin], [-sin, cos]].
    """
    c, s = math.cos(rotation), math.sin(rotation)
    t = np.array([[1.0, 0.0, offset[0]], [0.0, 1.0, offset[1]], [0.0, 0.0, 1.0]])
    r = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    sc = np.diag([scale[0], scale[1], 1.0])
    return t @ r @ sc


STORAGES = ("rgba8", "half", "float")  # how an image's texels are stored, by pixel dtype
_STORAGE_OF_DTYPE = {np.dtype(np.uint8): "rgba8", np.dtype(np.float16): "half",
                     np.dtype(np.float32): "float"}


class TextureImage:
    """One image as texture slots read it: its texels as stored, and how a lookup decodes them.

    `pixels` is (H, W, 4) uint8 (8-bit files), float16 (16-bit files, k / 65535) or float32
    (float files), row 0 at the top, RGBA. `srgb`: RGB is sRGB-encoded and is decoded to linear
    per texel (alpha never is). Two entries may share one `pixels` array (one file read as
    colour and as data); the atlas stores such an array once. `label` says where it came from
    (e.g. "images[0] 'wood.png'").
    """

    def __init__(self, pixels: np.ndarray, srgb: bool = False, label: str = ""):
        pixels = np.asarray(pixels)
        if pixels.ndim != 3 or pixels.shape[2] != 4 or pixels.dtype not in _STORAGE_OF_DTYPE:
            raise ValueError(f"texture pixels must be (H, W, 4) uint8, float16 or float32, "
                             f"not {pixels.shape} {pixels.dtype}")
        self.pixels = pixels
        self.srgb = bool(srgb)
        self.label = label

    @property
    def storage(self) -> str:
        """'rgba8', 'half' or 'float' (one of STORAGES)."""
        return _STORAGE_OF_DTYPE[self.pixels.dtype]

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width) in texels."""
        return int(self.pixels.shape[0]), int(self.pixels.shape[1])

    def linear(self) -> np.ndarray:
        """float32 (H, W, 4): the values a lookup reads at texel centres (decoded, linear)."""
        if self.pixels.dtype == np.uint8:
            out = self.pixels.astype(np.float32) / np.float32(255.0)
            if self.srgb:
                out[..., :3] = SRGB8_TO_LINEAR[self.pixels[..., :3]]
            return out
        out = self.pixels.astype(np.float32)
        if self.srgb:
            out[..., :3] = srgb_to_linear(out[..., :3])
        return out

    def __eq__(self, other) -> bool:
        return (isinstance(other, TextureImage) and self.srgb == other.srgb
                and self.pixels.dtype == other.pixels.dtype
                and np.array_equal(self.pixels, other.pixels))

    __hash__ = None

    def __repr__(self) -> str:
        h, w = self.shape
        return f"TextureImage({w}x{h} {self.storage}{' sRGB' if self.srgb else ''} {self.label!r})"


@dataclass(frozen=True)
class TextureRef:
    """One texture slot of a material: which image, which UV set, how to wrap and transform UVs.

    `texture` indexes `MeshAsset.images` (an entry that says how this slot decodes the image).
    `wrap_s` / `wrap_t` are "repeat" | "clamp" | "mirror" (glTF REPEAT, CLAMP_TO_EDGE,
    MIRRORED_REPEAT). Filters are recorded as written ("nearest", "linear",
    "linear_mipmap_linear", ...; None = not specified); the sampler may ignore them.
    `transform` is the KHR_texture_transform matrix as a row-major 3x3 tuple (identity if absent).
    """

    texture: int
    uv_set: int = 0
    wrap_s: str = "repeat"
    wrap_t: str = "repeat"
    mag_filter: Optional[str] = None
    min_filter: Optional[str] = None
    transform: tuple[tuple[float, float, float], ...] = IDENTITY_UV_TRANSFORM

    @property
    def matrix(self) -> np.ndarray:
        """The UV transform as a float32 (3, 3) array: uv' = (matrix @ [u, v, 1])[:2]."""
        return np.array(self.transform, dtype=np.float32)

    @property
    def has_transform(self) -> bool:
        return self.transform != IDENTITY_UV_TRANSFORM


@dataclass(frozen=True)
class PbrMaterial:
    """glTF 2.0 metallic-roughness material and its layers (other formats are mapped onto it).

    Each factor multiplies its texture; a slot without a texture is its factor alone. Channels:
      base colour RGBA (sRGB colour, alpha linear); metallic-roughness G = roughness,
      B = metallic; normal tangent space RGB; emissive RGB (sRGB); transmission R.
      KHR_materials_clearcoat: clearcoat R; clearcoat roughness G; clearcoat normal RGB (tangent
        space, same tangents as the base normal map, scaled by `clearcoat_normal_scale`).
      KHR_materials_sheen: sheen colour RGB (sRGB); sheen roughness A.
      KHR_materials_specular: specular (strength) A; specular colour RGB (sRGB). glTF's
        defaults (1, white) leave the dielectric Fresnel of the base as it was.
      KHR_materials_volume: `thickness_factor` is recorded, not used (a path tracer follows the
        real geometry) except that zero means thin-walled; the interior absorbs so that light
        keeps `attenuation_color` after `attenuation_distance` metres (Beer's law; +inf = none).
        The thickness texture is not loaded.
    `emissive_factor` already includes KHR_materials_emissive_strength (radiance-scaled, may
    exceed 1). `alpha_mode` / `alpha_cutoff` / `double_sided` are recorded as written.
    `extensions`: the glTF material extensions the file gives this material, sorted (those
    the loader does not implement included: `info` marks them).
    """

    name: str
    base_color_factor: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    metallic_factor: float = 1.0
    roughness_factor: float = 1.0
    emissive_factor: tuple[float, float, float] = (0.0, 0.0, 0.0)
    transmission_factor: float = 0.0
    ior: float = 1.5
    normal_scale: float = 1.0
    alpha_mode: str = "OPAQUE"
    alpha_cutoff: float = 0.5
    double_sided: bool = True  # glTF's doubleSided (false: back faces culled); other formats shade both sides
    base_color_texture: Optional[TextureRef] = None
    metallic_roughness_texture: Optional[TextureRef] = None
    normal_texture: Optional[TextureRef] = None
    emissive_texture: Optional[TextureRef] = None
    transmission_texture: Optional[TextureRef] = None
    clearcoat_factor: float = 0.0
    clearcoat_texture: Optional[TextureRef] = None
    clearcoat_roughness_factor: float = 0.0
    clearcoat_roughness_texture: Optional[TextureRef] = None
    clearcoat_normal_texture: Optional[TextureRef] = None
    clearcoat_normal_scale: float = 1.0
    sheen_color_factor: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sheen_color_texture: Optional[TextureRef] = None
    sheen_roughness_factor: float = 0.0
    sheen_roughness_texture: Optional[TextureRef] = None
    specular_factor: float = 1.0
    specular_texture: Optional[TextureRef] = None
    specular_color_factor: tuple[float, float, float] = (1.0, 1.0, 1.0)
    specular_color_texture: Optional[TextureRef] = None
    has_volume: bool = False  # KHR_materials_volume present
    thickness_factor: float = 0.0
    attenuation_color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    attenuation_distance: float = math.inf
    extensions: tuple[str, ...] = ()

    @property
    def thin_walled(self) -> bool:
        """Transmission through an infinitely thin shell (no refraction into a volume).

        glTF: transmission without KHR_materials_volume is thin-walled, and so is a volume of
        thickness 0. Meaningful for transmissive materials only.
        """
        return not self.has_volume or self.thickness_factor <= 0.0

    @property
    def texture_slots(self) -> dict[str, TextureRef]:
        """The slots that hold a texture, by name."""
        slots = {
            "base_color": self.base_color_texture,
            "metallic_roughness": self.metallic_roughness_texture,
            "normal": self.normal_texture,
            "emissive": self.emissive_texture,
            "transmission": self.transmission_texture,
            "clearcoat": self.clearcoat_texture,
            "clearcoat_roughness": self.clearcoat_roughness_texture,
            "clearcoat_normal": self.clearcoat_normal_texture,
            "sheen_color": self.sheen_color_texture,
            "sheen_roughness": self.sheen_roughness_texture,
            "specular": self.specular_texture,
            "specular_color": self.specular_color_texture,
        }
        return {k: v for k, v in slots.items() if v is not None}

    @property
    def is_emissive(self) -> bool:
        return max(self.emissive_factor) > 0.0


@dataclass
class TriangleMesh:
    """One drawable piece: a glTF primitive, or one material group of an OBJ.

    positions (V, 3) float32 (world space in `MeshAsset.meshes`, local in `InstancedMesh`).
    indices (T, 3) int32, counter-clockwise seen from the front (see module docs for instances).
    normals (V, 3) float32 unit, or None.       uv0 / uv1 (V, 2) float32 (glTF UV frame), or None.
    tangents (V, 4) float32 (see module docs), present whenever the material has a normal map
    (base or clearcoat).
    colors (V, 4) float32 linear RGBA vertex colours (glTF COLOR_0, PLY colours), or None; per glTF
    they multiply the base colour (alpha included).
    material indexes `MeshAsset.materials`.
    """

    positions: np.ndarray
    indices: np.ndarray
    material: int = 0
    normals: Optional[np.ndarray] = None
    uv0: Optional[np.ndarray] = None
    uv1: Optional[np.ndarray] = None
    tangents: Optional[np.ndarray] = None
    colors: Optional[np.ndarray] = None
    name: str = ""

    def uv(self, uv_set: int) -> Optional[np.ndarray]:
        """The UV set a `TextureRef.uv_set` names (0 or 1), or None."""
        if uv_set == 0:
            return self.uv0
        if uv_set == 1:
            return self.uv1
        raise ValueError(f"only UV sets 0 and 1 exist, not {uv_set}")

    @property
    def vertex_count(self) -> int:
        return int(len(self.positions))

    @property
    def triangle_count(self) -> int:
        return int(len(self.indices))


def normal_matrix(m3: np.ndarray) -> np.ndarray:
    """The matrix that transforms normals under m3: its cofactor matrix, sign-corrected.

    cofactor(M) = det(M) * inverse(M)^T gives the directions of the inverse transpose and stays
    defined for a singular (flattening) M, where it maps every normal onto the flattened plane's
    normal. Multiplied by sign(det) so that normals keep pointing to the same side.
    """
    m3 = np.asarray(m3, dtype=np.float64)
    cofactor = np.array([np.cross(m3[1], m3[2]), np.cross(m3[2], m3[0]), np.cross(m3[0], m3[1])])
    return cofactor if np.linalg.det(m3) >= 0.0 else -cofactor


@dataclass
class InstancedMesh:
    """One mesh stored once in its local frame, drawn once per object-to-world matrix.

    `mesh` is local-space (module docs, "Instances"); `matrices` is float64 (N, 4, 4), N >= 1,
    rows of a matrix acting on column vectors, last row (0, 0, 0, 1).
    """

    mesh: TriangleMesh
    matrices: np.ndarray

    @property
    def instance_count(self) -> int:
        return int(len(self.matrices))

    def placed(self, k: int) -> TriangleMesh:
        """Instance k as a world-space mesh, following the conventions of world meshes."""
        return place_mesh(self.mesh, self.matrices[k], name=f"{self.mesh.name}#{k}")


def place_mesh(mesh: TriangleMesh, matrix, name: Optional[str] = None) -> TriangleMesh:
    """`mesh` placed with the object-to-world `matrix` (4x4, acting on column vectors): the one
    function that moves triangles, for instances and for scene objects alike (module docs,
    "Instances"). Positions by the matrix; normals by its cofactor matrix (`normal_matrix`, so
    a flattening matrix still gives the plane's normal), unit length; tangents by its 3x3 part,
    unit length (they stay orthogonal to the normals: M t . cofactor(M) n = det(M) t . n), their
    handedness flipped, and the winding reversed, under a mirroring matrix. Float64 arithmetic,
    float32 results; UVs and colours are shared with `mesh`."""
    m = np.asarray(matrix, dtype=np.float64)
    m3 = m[:3, :3]
    mirrored = np.linalg.det(m3) < 0.0
    positions = placed_points(mesh.positions, m)
    normals = tangents = None
    if mesh.normals is not None:
        n = placed_normals(mesh.normals, m3)
        normals = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    if mesh.tangents is not None:
        t = mesh.tangents[:, :3].astype(np.float64) @ m3.T
        t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-30)
        w = mesh.tangents[:, 3:4] * (-1.0 if mirrored else 1.0)
        tangents = np.concatenate([t, w], axis=1)
    return TriangleMesh(
        positions=as_float32(positions),
        indices=np.ascontiguousarray(mesh.indices[:, [0, 2, 1]] if mirrored else mesh.indices),
        material=mesh.material, normals=as_float32(normals), uv0=mesh.uv0, uv1=mesh.uv1,
        tangents=as_float32(tangents), colors=mesh.colors, name=mesh.name if name is None else name)


def placed_points(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """(P, 3) points under a 4x4 matrix, in float64."""
    return points.astype(np.float64) @ matrix[:3, :3].T + matrix[:3, 3]


def placed_normals(normals: np.ndarray, m3: np.ndarray) -> np.ndarray:
    """(P, 3) normals under the 3x3 part `m3` of a placement, by its cofactor matrix, in float64
    and not normalised (the loader repairs the ones that come out zero)."""
    return normals.astype(np.float64) @ normal_matrix(m3).T


def as_float32(a: Optional[np.ndarray]) -> Optional[np.ndarray]:
    """A contiguous float32 copy of an optional attribute array (None stays None)."""
    return None if a is None else np.ascontiguousarray(a, dtype=np.float32)


@dataclass
class MeshAsset:
    """Everything one model file provides.

    `meshes`: world-space meshes (placed once); `instanced`: meshes stored once with their
    object-to-world matrices (module docs, "Instances"). `images[i]` is a `TextureImage` (its
    label says where it came from, its `srgb` how lookups decode it). `bounds` is float32 (2, 3):
    world-space min and max corners of all referenced vertices of every mesh and every instance.
    `extensions_used`: the file's glTF extensionsUsed; `extensions_ignored`: those of them this
    loader does not implement (the loader warned about them).
    """

    meshes: list[TriangleMesh]
    materials: list[PbrMaterial]
    images: list[TextureImage] = field(default_factory=list)
    bounds: np.ndarray = field(default_factory=lambda: np.zeros((2, 3), dtype=np.float32))
    path: Optional[Path] = None
    instanced: list[InstancedMesh] = field(default_factory=list)
    extensions_used: tuple[str, ...] = ()
    extensions_ignored: tuple[str, ...] = ()

    @property
    def triangle_count(self) -> int:
        """Unique triangles: each instanced mesh counts once."""
        return (sum(m.triangle_count for m in self.meshes)
                + sum(i.mesh.triangle_count for i in self.instanced))

    @property
    def instanced_triangle_count(self) -> int:
        """Triangles the instances draw: each instanced mesh times its instance count."""
        return sum(i.mesh.triangle_count * i.instance_count for i in self.instanced)

    @property
    def drawn_triangle_count(self) -> int:
        """Every triangle the model shows: world meshes plus what the instances draw."""
        return sum(m.triangle_count for m in self.meshes) + self.instanced_triangle_count

    @property
    def vertex_count(self) -> int:
        """Unique vertices: each instanced mesh counts once."""
        return (sum(m.vertex_count for m in self.meshes)
                + sum(i.mesh.vertex_count for i in self.instanced))

"""Plain-data triangle meshes, PBR materials and textures, as `mesh_loader` produces them.

Everything is numpy and dataclasses (no Taichi): the renderer uploads these arrays, the BVH builder
reads `positions` and `indices`, and the texture atlas (`renderer.scene.textures`) packs `images`.

Conventions (shared by every loader, whatever the file format stores):

- Positions are in WORLD space, metres: node transforms are already applied, and a mesh used by
  two nodes appears twice. A triangle's vertices are counter-clockwise seen from its front side,
  also under mirroring node transforms (the loader reverses the winding when det(M) < 0).
- Normals are unit length, transformed with the inverse transpose of the node matrix. `None`
  means the file had none: shade with the geometric normal (glTF prescribes flat shading then).
- UV sets follow glTF: u to the right, v DOWN, (0, 0) is the top-left corner of the image and
  image row 0 is the top row. OBJ, PLY and other v-up formats are flipped at load (v -> 1 - v).
  The KHR_texture_transform matrix of a `TextureRef` is NOT applied to the stored UVs: the sampler
  applies it per texture slot, `uv' = (ref.matrix @ [u, v, 1])[:2]`.
- Tangents are (xyz, w): a unit tangent along increasing u, orthogonal to the normal, and the
  handedness w = +-1. The bitangent is `B = w * cross(N, T)`; it points "up" in the image
  (towards decreasing stored v), which is the +y of a glTF/MikkTSpace tangent-space normal map.
  A shading normal is `normalize(T * n.x + B * n.y + N * n.z)` with
  `n = (2 * texel.rgb - 1) * (normal_scale, normal_scale, 1)`.
- Colour: every image in `MeshAsset.images` holds LINEAR values. Slots that glTF defines as sRGB
  (base colour, emissive) are converted from sRGB to linear at load time (the alpha channel is
  always linear); data slots (metallic-roughness, normal, transmission) are kept as decoded. An
  image used both as colour and as data is stored twice, once per encoding. So the sampler never
  needs to know about colour spaces.
- Images are float32 (H, W, 4) RGBA: grey images are replicated to RGB and a missing alpha is 1.
  8-bit files decode to k / 255, 16-bit files to k / 65535.
- Occlusion textures are ignored on purpose: a path tracer computes occlusion itself, and
  multiplying a baked ambient-occlusion map on top would darken the image twice.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

from renderer.scene.model import MaterialSpec

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


@dataclass(frozen=True)
class TextureRef:
    """One texture slot of a material: which image, which UV set, how to wrap and transform UVs.

    `texture` indexes `MeshAsset.images` (already in the right colour space for this slot).
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
    """glTF 2.0 metallic-roughness material (other formats are mapped onto it by the loader).

    Texture channels: base colour RGBA (sRGB in the file, linear here), metallic-roughness
    (G = roughness, B = metallic, linear), normal (tangent space, linear), emissive (sRGB in the
    file, linear here), transmission (R channel, linear). Each factor multiplies its texture.
    `emissive_factor` already includes KHR_materials_emissive_strength (it is radiance-scaled and
    may exceed 1). `alpha_mode` / `alpha_cutoff` / `double_sided` are recorded, not interpreted.
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
    double_sided: bool = False
    base_color_texture: Optional[TextureRef] = None
    metallic_roughness_texture: Optional[TextureRef] = None
    normal_texture: Optional[TextureRef] = None
    emissive_texture: Optional[TextureRef] = None
    transmission_texture: Optional[TextureRef] = None

    @property
    def texture_slots(self) -> dict[str, TextureRef]:
        """The slots that hold a texture, by name."""
        slots = {
            "base_color": self.base_color_texture,
            "metallic_roughness": self.metallic_roughness_texture,
            "normal": self.normal_texture,
            "emissive": self.emissive_texture,
            "transmission": self.transmission_texture,
        }
        return {k: v for k, v in slots.items() if v is not None}

    @property
    def is_emissive(self) -> bool:
        return max(self.emissive_factor) > 0.0

    def approximate_spec(self) -> MaterialSpec:
        """The closest of the renderer's three simple kinds, ignoring textures.

        transmission >= 0.5 -> dielectric (tint = base colour), else metallic >= 0.5 -> conductor
        (F0 = base colour), else diffuse (albedo = base colour). Roughness and emission carry over.
        Meant for renderers that do not (yet) evaluate the full metallic-roughness model.
        """
        rgb = tuple(float(c) for c in self.base_color_factor[:3])
        if self.transmission_factor >= 0.5:
            kind = "dielectric"
        elif self.metallic_factor >= 0.5:
            kind = "conductor"
        else:
            kind = "diffuse"
        return MaterialSpec(
            name=self.name,
            kind=kind,
            base_color=rgb,
            roughness=float(min(max(self.roughness_factor, 0.0), 1.0)),
            ior=float(self.ior),
            emission=tuple(float(c) for c in self.emissive_factor),
        )


@dataclass
class TriangleMesh:
    """One drawable piece: a glTF primitive placed by one node, or one material group of an OBJ.

    positions (V, 3) float32, world space.      indices (T, 3) int32, counter-clockwise.
    normals (V, 3) float32 unit, or None.       uv0 / uv1 (V, 2) float32 (glTF UV frame), or None.
    tangents (V, 4) float32 (see module docs), present whenever the material has a normal map.
    colors (V, 4) float32 linear RGBA vertex colours (glTF COLOR_0, PLY colours), or None; per glTF
    they multiply the base colour.
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


@dataclass
class MeshAsset:
    """Everything one model file provides.

    `images[i]` is float32 (H, W, 4) linear RGBA (see module docs); `image_labels[i]` says where it
    came from and how it was decoded, e.g. "images[0] 'wood.png' (sRGB -> linear)".
    `bounds` is float32 (2, 3): world-space min and max corners of all referenced vertices.
    """

    meshes: list[TriangleMesh]
    materials: list[PbrMaterial]
    images: list[np.ndarray] = field(default_factory=list)
    bounds: np.ndarray = field(default_factory=lambda: np.zeros((2, 3), dtype=np.float32))
    image_labels: list[str] = field(default_factory=list)
    path: Optional[Path] = None

    @property
    def triangle_count(self) -> int:
        return sum(m.triangle_count for m in self.meshes)

    @property
    def vertex_count(self) -> int:
        return sum(m.vertex_count for m in self.meshes)

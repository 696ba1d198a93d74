"""Load triangle-mesh models (glTF 2.0 / GLB, OBJ + MTL, PLY, STL) into a `MeshAsset`.

`load_mesh_asset(path)` is the one entry point. It returns triangle meshes (world-space ones and
instanced ones), PBR materials and images at their own precision (conventions in
`renderer.scene.mesh_model`), or raises a one-line `SceneError` naming the file and the problem.

How each format is read
-----------------------
glTF / GLB
    Read here with the standard library (`json`, `struct` for the GLB container) and numpy for
    accessors; images are decoded with Pillow (16-bit PNGs with OpenCV, which keeps their 16
    bits). trimesh's glTF importer is not used because it drops what a path tracer needs:
    TEXCOORD_1, TANGENT, samplers (wrap modes), KHR_texture_transform and the original texture
    indices, and it flips V. Supported: the node hierarchy with matrix or TRS
    transforms, triangles / strips / fans (points and lines are skipped with a warning), indexed
    and non-indexed primitives, sparse and normalized accessors (so KHR_mesh_quantization works),
    embedded, data-URI and external buffers and images, metallic-roughness materials with base
    colour, metallic-roughness, normal and emissive textures (occlusion is ignored: the path
    tracer computes it), and the extensions in SUPPORTED_GLTF_EXTENSIONS:
    KHR_materials_emissive_strength, _transmission, _ior, _clearcoat, _sheen, _specular, _volume,
    KHR_texture_transform, KHR_mesh_quantization, EXT_texture_webp, EXT_mesh_gpu_instancing.
    A mesh placed by one node becomes world-space meshes; a mesh placed by two or more nodes, or
    by a node with EXT_mesh_gpu_instancing (per-instance TRANSLATION / ROTATION / SCALE, applied
    before the node's world matrix), is stored once with one matrix per placement
    (`MeshAsset.instanced`). A primitive without a material gets the glTF default material
    (white, metallic 1, roughness 1), appended after the file's materials. Skins and morph
    targets are ignored (meshes are placed in their bind pose by their node transform); cameras
    and lights too. A file that *requires* any other extension (Draco, meshopt, KTX2/Basis
    textures) is refused; other extensions it merely *uses* are ignored with one warning that
    lists them.
OBJ + MTL
    Geometry through trimesh (`trimesh.exchange.obj.load_obj`, one mesh per material); the MTL
    files are parsed here, so that missing libraries and textures are reported. Mapping:
      Kd -> base colour (default 0.8 grey); d (or 1 - Tr) -> base colour alpha.
      Roughness: Pr if given; else 1.0 when Ks is absent or black (no highlight: matte); else
        from the Phong exponent, alpha = sqrt(2 / (Ns + 2)) (the Beckmann/Phong correspondence of
        Walter et al. 2007), roughness = sqrt(alpha); without Ns, 0.5.
      Metallic: Pm if given; else 1 for a "mirror" (black Kd, non-black Ks; base colour = Ks),
        else 0.
      Ke -> emission (times map_Ke). Ni -> ior when > 1 (Ni = 1 is what most exporters write for
        "unset"; 1.5 is used then). Glass: illum 4, 6, 7 or 9 with d < 1 -> transmission = 1 - d
        (and alpha 1); otherwise d < 1 is alpha blending.
      Textures: map_Kd (base colour, sRGB), map_Ke (emissive, sRGB), norm (normal map), and
        map_Bump / bump only when the image is a tangent-space normal map (blue on average, as
        Blender writes them); height-map bumps are ignored with a warning. Options -o and -s
        become a UV transform, -clamp on becomes clamp wrapping; other options are skipped.
        map_Ka, map_Ks, map_Ns, map_d, map_Pr, map_Pm are ignored.
PLY / STL
    Geometry through trimesh (`load_ply` / `load_stl`). One grey material (base 0.8, metallic 0,
    roughness 0.5, as the TOML scene defaults). PLY vertex colours are kept as
    `TriangleMesh.colors`, decoded as sRGB (they are display-referred in every writer we know),
    and the material's base colour is then white so that the colours show unchanged. Face colours
    are ignored. A PLY `comment TextureFile` image with per-vertex or per-face UVs becomes the
    base colour texture.

Checks (all formats)
--------------------
SceneError: missing file, unsupported extension, unreadable or truncated data, no triangles at
all, non-finite positions / UVs / colours, vertex indices out of range, a missing buffer or
material library file, an image that does not decode, a required glTF extension we do not
implement, a glTF node reached twice (a cycle, or a node with two parents), and any other
failure inside a reader (trimesh's included), always in one line naming the model file.
Memory: what the file declares is charged to the scene's `MemoryLedger` (renderer.scene.limits)
before it is allocated: the file itself, external buffers, each accessor's count (8 bytes a
component, with or without a bufferView, sparse ones too), each mesh build (MESH_BUILD_* and
TANGENT_* bytes per vertex and triangle), trimesh's parsing (TRIMESH_PARSE_BYTES_PER_BYTE) and each
image from its header (its texels kept IMAGE_COPIES times, its decoding's peak); what would pass
the budget is refused, naming what, how much and the limit.
References: glTF URIs, OBJ `mtllib` and texture maps and a PLY `TextureFile` are resolved with
symlinks followed and must lie inside the model's folder, unless `LoadOptions.allow_outside_files`.
Warning (`MeshWarning`, one line naming the model file): a missing texture file (one warning per
file, naming the materials that use it; they keep their factors alone, as other viewers do),
glTF extensions used but not implemented.
Warning (`DegenerateTrianglesWarning`, one per file with the count): triangles with a repeated
vertex index or zero area are removed. "Zero area" is tested in float64 on the world-space
positions (local ones for instanced meshes), relative to the triangle's size: twice the area
below 1e-12 times the squared longest edge (height < 1e-12 of its length). Normals are
transformed with the cofactor matrix of the node transform (det(M) times the inverse transpose:
the same directions, and still defined when a zero scale flattens the model;
`mesh_model.normal_matrix`). Normals that are zero or non-finite are replaced by the
area-weighted average of the adjacent face normals (`MeshWarning`).
"""
from __future__ import annotations

import base64
import dataclasses
import io
import json
import math
import os
import re
import struct
import warnings
from pathlib import Path
from typing import Callable, Optional, Union
from urllib.parse import unquote

import numpy as np

from renderer.scene.errors import SceneError
from renderer.scene.limits import MemoryLedger
from renderer.scene.load_options import LoadOptions
from renderer.scene.mesh_model import (
    InstancedMesh,
    MeshAsset,
    PbrMaterial,
    TextureImage,
    TextureRef,
    TriangleMesh,
    normal_matrix,
    uv_transform_matrix,
)
from renderer.scene.references import missing_file_problem, resolve_reference
from renderer.scene.srgb import srgb_to_linear

PathLike = Union[str, os.PathLike]

MESH_EXTENSIONS = (".gltf", ".glb", ".obj", ".ply", ".stl")

# glTF extensions whose data this loader reads; a file may *require* only these.
SUPPORTED_GLTF_EXTENSIONS = frozenset({
    "KHR_materials_emissive_strength",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_volume",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
    "EXT_texture_webp",
    "EXT_mesh_gpu_instancing",
})

DEGENERATE_RELATIVE_AREA = 1e-12  # see the module docs ("Checks")

# Memory the readers need beyond what the file declares (renderer.scene.limits), upper bounds of
# what tests/scene/test_input_limits.py measures with tracemalloc: building one mesh (world
# positions, attributes and degenerate-triangle tests in float64) per vertex and per triangle,
# generating its tangents (for a normal map) per vertex and per triangle, and trimesh's parsing
# of OBJ / PLY / STL per byte of the file.
MESH_BUILD_BYTES_PER_VERTEX = 400
MESH_BUILD_BYTES_PER_TRIANGLE = 400
TANGENT_BYTES_PER_VERTEX = 250
TANGENT_BYTES_PER_TRIANGLE = 500
TRIMESH_PARSE_BYTES_PER_BYTE = 20


class MeshWarning(UserWarning):
    """Something in a model file was repaired or skipped; the model still loads."""


class DegenerateTrianglesWarning(MeshWarning):
    """Zero-area triangles or triangles with a repeated vertex were removed."""


# ---------------------------------------------------------------------------------------------
# public helpers


def load_mesh_asset(path: PathLike, options: Optional[LoadOptions] = None,
                    ledger: Optional[MemoryLedger] = None) -> MeshAsset:
    """Load a .gltf, .glb, .obj, .ply or .stl model. See the module docs for what is read.

    `options`: the memory budget and whether references may leave the model's folder (default:
    `LoadOptions()`); `ledger`: where the scene adds up what its files were charged (default: a
    new one over the options' budget)."""
    name = path  # errors show the path exactly as the caller gave it
    file = Path(path)
    if not file.is_file():
        problem = missing_file_problem(file)
        raise SceneError(name, "model file not found" if problem == "file not found" else problem)
    extension = file.suffix.lower()
    if extension not in MESH_EXTENSIONS:
        raise SceneError(
            name,
            f"unsupported model format '{file.suffix or '(none)'}' "
            f"(expected one of {', '.join(MESH_EXTENSIONS)})",
        )
    options = options or LoadOptions()
    builder = _AssetBuilder(name, file, options, ledger or MemoryLedger(options.budget))
    try:
        builder.charge_file(file, "the file")
        if extension in (".gltf", ".glb"):
            _GltfReader(builder).read()
        elif extension == ".obj":
            _load_obj(builder)
        elif extension == ".ply":
            _load_ply(builder)
        else:
            _load_stl(builder)
        return builder.finish()
    except SceneError:
        raise
    except Exception as e:  # noqa: BLE001 - the readers (ours, trimesh, numpy) raise many types
        # for bad data; every one is a problem with this file, said in one line
        detail = f"{type(e).__name__}: {e}" if str(e) else type(e).__name__
        raise SceneError(name, f"cannot read {extension[1:].upper()} file ({detail})") from e


def frame_camera(bounds, fov_deg: float, aspect: float = 1.0,
                 direction=(0.0, 0.25, 1.0), margin: float = 1.1):
    """(position, look_at) that frames a bounding box: look at its centre from `direction`.

    The camera backs off until the bounding sphere fits the narrower of the vertical field of view
    `fov_deg` (degrees) and the horizontal one implied by `aspect` (width / height), times `margin`.
    """
    b = np.asarray(bounds, dtype=np.float64).reshape(2, 3)
    if not np.all(np.isfinite(b)):
        raise ValueError("bounds must be finite")
    centre = 0.5 * (b[0] + b[1])
    radius = 0.5 * float(np.linalg.norm(b[1] - b[0]))
    if radius <= 0.0:
        radius = 1.0  # a single point: frame a unit sphere around it
    half_v = math.radians(min(max(fov_deg, 1e-3), 179.0)) / 2.0
    half_h = math.atan(math.tan(half_v) * max(aspect, 1e-6))
    half = min(half_v, half_h)
    distance = margin * radius / math.sin(half)
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    position = centre + d * distance
    return tuple(float(v) for v in position), tuple(float(v) for v in centre)


def vertex_normals(positions: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Area-weighted average of adjacent face normals, unit length ((0, 0, 1) where undefined)."""
    p = np.asarray(positions, dtype=np.float64)
    tri = np.asarray(indices, dtype=np.int64)
    face = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])  # length = 2 * area
    acc = np.zeros_like(p)
    for k in range(3):
        np.add.at(acc, tri[:, k], face)
    return _normalize_or(acc, np.array([0.0, 0.0, 1.0]))


def generate_tangents(positions: np.ndarray, normals: np.ndarray, uvs: np.ndarray,
                      indices: np.ndarray) -> np.ndarray:
    """Per-vertex tangents (V, 4) from UV derivatives, MikkTSpace-like.

    Each triangle's tangent (direction of increasing u) and bitangent (direction of increasing
    "v up", i.e. decreasing stored v, see `mesh_model`) are accumulated at its corners weighted by
    the corner angle, then the tangent is orthogonalised against the vertex normal
    (Gram-Schmidt) and w = sign(dot(cross(N, T), B)). Triangles whose UVs are degenerate
    contribute nothing; a vertex left without a tangent gets an arbitrary unit vector orthogonal
    to its normal (w = 1). Unlike MikkTSpace, vertices are not split where mirrored UV islands
    meet; such vertices get w = +1 or -1 by majority.
    """
    p = np.asarray(positions, dtype=np.float64)
    n = _normalize_or(np.asarray(normals, dtype=np.float64), np.array([0.0, 0.0, 1.0]))
    uv = np.asarray(uvs, dtype=np.float64) * np.array([1.0, -1.0])  # to the v-up frame
    tri = np.asarray(indices, dtype=np.int64)
    p0, p1, p2 = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
    t0, t1, t2 = uv[tri[:, 0]], uv[tri[:, 1]], uv[tri[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    d1, d2 = t1 - t0, t2 - t0
    r = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    sign = np.sign(r)[:, None]
    # Dividing by r only rescales; its sign keeps the directions right. Faces with r == 0 drop out.
    sdir = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * sign
    tdir = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * sign
    sdir = _normalize_or(sdir, np.zeros(3))
    tdir = _normalize_or(tdir, np.zeros(3))

    corners = (p0, p1, p2)
    t_acc = np.zeros_like(p)
    b_acc = np.zeros_like(p)
    for k in range(3):
        a = corners[(k + 1) % 3] - corners[k]
        b = corners[(k + 2) % 3] - corners[k]
        cos = np.einsum("ij,ij->i", _normalize_or(a, np.zeros(3)), _normalize_or(b, np.zeros(3)))
        angle = np.arccos(np.clip(cos, -1.0, 1.0))[:, None]
        np.add.at(t_acc, tri[:, k], sdir * angle)
        np.add.at(b_acc, tri[:, k], tdir * angle)

    t = t_acc - n * np.einsum("ij,ij->i", n, t_acc)[:, None]
    length = np.linalg.norm(t, axis=1)
    scale = np.maximum(np.abs(t_acc).max(axis=1), 1e-300)
    missing = ~(length > 1e-6 * scale) | ~np.isfinite(length)
    t = np.where(missing[:, None], _any_perpendicular(n), t / np.where(missing, 1.0, length)[:, None])
    w = np.where(np.einsum("ij,ij->i", np.cross(n, t), b_acc) < 0.0, -1.0, 1.0)
    return np.concatenate([t, w[:, None]], axis=1).astype(np.float32)


# ---------------------------------------------------------------------------------------------
# numeric helpers


def _normalize_or(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Rows of v scaled to unit length; rows that are zero or non-finite become `fallback`."""
    v = np.asarray(v, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        length = np.sqrt(np.einsum("ij,ij->i", v, v))
    ok = np.isfinite(length) & (length > 0.0)
    out = v / np.where(ok, length, 1.0)[:, None]
    if not ok.all():
        out[~ok] = fallback
    return out


def _any_perpendicular(n: np.ndarray) -> np.ndarray:
    """A unit vector orthogonal to each (unit) row of n (the branchless frame of Duff et al. 2017)."""
    s = np.where(n[:, 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (s + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    return np.stack([1.0 + s * n[:, 0] ** 2 * a, s * b, -s * n[:, 0]], axis=1)


def _quaternion_matrices(q) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of unit quaternions (N, 4) given as (x, y, z, w), glTF's order.
    Quaternions are normalised first; a zero or non-finite one is the identity."""
    q = np.asarray(q, dtype=np.float64).reshape(-1, 4)
    with np.errstate(over="ignore", invalid="ignore"):
        norm = np.linalg.norm(q, axis=1)
    ok = np.isfinite(norm) & (norm > 0.0)
    q = np.where(ok[:, None], q / np.where(ok, norm, 1.0)[:, None], [0.0, 0.0, 0.0, 1.0])
    x, y, z, w = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], axis=1)


def _trs_matrices(translation, rotation, scale) -> np.ndarray:
    """(N, 4, 4) matrices T @ R @ S (glTF's TRS order) from (N, 3), (N, 4), (N, 3) arrays."""
    m = np.zeros((len(translation), 4, 4))
    m[:, :3, :3] = _quaternion_matrices(rotation) * np.asarray(scale, dtype=np.float64)[:, None, :]
    m[:, :3, 3] = translation
    m[:, 3, 3] = 1.0
    return m


def _rgba(channels: np.ndarray, opaque) -> np.ndarray:
    """(H, W, 4) from (H, W) grey, (H, W, 2) grey + alpha, (H, W, 3) RGB or (H, W, 4) RGBA."""
    if channels.ndim == 2:
        channels = channels[:, :, None]
    h, w, c = channels.shape
    out = np.empty((h, w, 4), dtype=channels.dtype)
    out[:, :, :3] = channels[:, :, :3] if c >= 3 else channels[:, :, :1]
    out[:, :, 3] = channels[:, :, c - 1] if c in (2, 4) else opaque
    return out


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
# Bytes per pixel while decoding (the decoder's own buffer and every numpy copy below, which
# tests/scene/test_input_limits.py checks against tracemalloc) and once decoded (RGBA texels).
_DECODE_PEAK = {"png16": 48, "grey16": 30, "float": 24, "8bit": 12}
_DECODED = {"png16": 8, "grey16": 8, "float": 16, "8bit": 4}
# A decoded image lives on in the scene's texture atlas and in the device's copy of that atlas.
IMAGE_COPIES = 3


def _is_16_bit_png(data: bytes) -> bool:
    # PNG signature, then the IHDR chunk: bit depth is byte 24 of the file.
    return data[:8] == _PNG_SIGNATURE and len(data) > 25 and data[24] == 16


def _image_header(data: bytes) -> tuple[int, int, str]:
    """(width, height, decoding) from an image's header alone, before anything is decoded;
    decoding is a key of _DECODED."""
    if data[:8] == _PNG_SIGNATURE and len(data) >= 25:
        width, height = struct.unpack_from(">II", data, 16)  # IHDR
        return width, height, "png16" if data[24] == 16 else "8bit"
    from PIL import Image

    with warnings.catch_warnings():  # the budget decides, not Pillow's fixed warning threshold
        warnings.simplefilter("ignore", Image.DecompressionBombWarning)
        with Image.open(io.BytesIO(data)) as im:  # lazy: reads the header
            width, height = im.size
            mode = im.mode
    decoding = "grey16" if mode.startswith("I;16") or mode == "I" else "float" if mode == "F" else "8bit"
    return width, height, decoding


def _decode_image(data: bytes) -> np.ndarray:
    """Decode PNG / JPEG / WebP / ... bytes to (H, W, 4) RGBA texels, still encoded.

    8-bit images stay uint8; 16-bit ones become float16 k / 65535 (OpenCV reads 16-bit colour
    PNGs, which Pillow would truncate to 8 bits); float images are float32.
    """
    if _is_16_bit_png(data):
        import cv2

        raw = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
        if raw is None:
            raise ValueError("OpenCV cannot decode this 16-bit PNG")
        if raw.ndim == 3 and raw.shape[2] >= 3:  # OpenCV's BGR(A) -> RGB(A)
            raw = raw[:, :, [2, 1, 0, 3][:raw.shape[2]]]
        unit = raw.astype(np.float32) / np.float32(np.iinfo(raw.dtype).max)
        return _rgba(unit, 1.0).astype(np.float16)
    from PIL import Image

    # The budget decided on the header's size; Pillow's own fixed threshold would only warn here.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", Image.DecompressionBombWarning)
        return _decode_with_pillow(Image.open(io.BytesIO(data)))


def _decode_with_pillow(opened) -> np.ndarray:
    with opened as im:
        im.load()
        if im.mode.startswith("I;16") or im.mode == "I":
            grey = np.clip(np.asarray(im).astype(np.float64) / 65535.0, 0.0, 1.0)
            return _rgba(grey.astype(np.float16), 1.0)
        if im.mode == "F":
            return _rgba(np.asarray(im, dtype=np.float32), 1.0)
        return np.ascontiguousarray(np.asarray(im.convert("RGBA"), dtype=np.uint8))


def _unit_values(pixels: np.ndarray) -> np.ndarray:
    """Stored texels as float64 in [0, 1] (8-bit ones as k / 255), undecoded."""
    return pixels / 255.0 if pixels.dtype == np.uint8 else pixels.astype(np.float64)


class _MissingTexture(Exception):
    """A texture file that is not there (the loader warns and goes on without it)."""

    def __init__(self, file_name: str):
        super().__init__(file_name)
        self.file_name = file_name


def _file_reader(builder: "_AssetBuilder", reference: str, what: str,
                 base: Optional[Path] = None) -> Callable[[], bytes]:
    """Reads a texture file the model names as `reference`, or raises _MissingTexture(reference)
    if it does not exist; a reference outside the model's folder is refused (SceneError)."""

    def load() -> bytes:
        target = builder.reference(reference, what, base)
        if not target.is_file():
            raise _MissingTexture(reference)
        builder.check_peak(f"{what} '{reference}'", target.stat().st_size)
        return target.read_bytes()

    return load


# ---------------------------------------------------------------------------------------------
# the part every format shares: materials, images, validation and placement of meshes


class _AssetBuilder:
    def __init__(self, name: PathLike, file: Path, options: LoadOptions, ledger: MemoryLedger):
        self.name = name
        self.file = file
        self.options = options
        self.ledger = ledger
        self.materials: list[PbrMaterial] = []
        self.meshes: list[TriangleMesh] = []
        self.instanced: list[InstancedMesh] = []
        self.images: list[TextureImage] = []
        self.extensions_used: tuple[str, ...] = ()
        self.extensions_ignored: tuple[str, ...] = ()
        self._image_index: dict[tuple, int] = {}
        self._decoded: dict[object, np.ndarray] = {}
        self._missing: dict[object, tuple[str, list[str]]] = {}  # key -> (file name, users)
        self.degenerate = 0
        self.repaired_normals = 0
        self.input_triangles = 0

    def error(self, message: str) -> SceneError:
        return SceneError(self.name, message)

    def charge(self, what: str, nbytes: int) -> None:
        """Book memory that stays allocated while the scene loads (renderer.scene.limits)."""
        self.ledger.charge(self.name, what, nbytes)

    def check_peak(self, what: str, nbytes: int) -> None:
        """Refuse a passing allocation that would not fit beside what is booked."""
        self.ledger.check_peak(self.name, what, nbytes)

    def charge_file(self, path: Path, what: str) -> None:
        """Book the bytes of a file about to be read whole."""
        self.charge(f"{what} ({path.name})", path.stat().st_size)

    def reference(self, reference: str, what: str, base: Optional[Path] = None) -> Path:
        """The file a reference of this model names (relative to `base`, by default the model's
        folder), refused when it lies outside the model's folder and that is not allowed."""
        return resolve_reference(self.file, self.name, reference, what,
                                 self.options.allow_outside_files, base)

    def warn(self, message: str) -> None:
        warnings.warn(f"{os.fspath(self.name)}: {message}", MeshWarning, stacklevel=4)

    def decoded_image(self, key, label: str, load: Callable[[], bytes]) -> np.ndarray:
        """The image `key` decoded (cached), as stored in the file (not colour-converted).
        Raises _MissingTexture when its file is missing."""
        if key not in self._decoded:
            data = load()
            try:
                width, height, decoding = _image_header(data)
            except Exception as e:  # Pillow raises many types for bad data
                raise self.error(f"cannot decode image {label} ({type(e).__name__}: {e})") from e
            pixels = width * height
            self.charge(f"image {label} ({width}x{height})", pixels * _DECODED[decoding] * IMAGE_COPIES)
            self.check_peak(f"decoding image {label} ({width}x{height})",
                            pixels * _DECODE_PEAK[decoding] + len(data))
            try:
                self._decoded[key] = _decode_image(data)
            except Exception as e:  # Pillow raises many types for bad data
                raise self.error(f"cannot decode image {label} ({type(e).__name__}: {e})") from e
        return self._decoded[key]

    def note_missing(self, key, file_name: str, user: str) -> None:
        """Remember that `user` (e.g. "material 'wood' base colour") wanted a missing file."""
        self._missing.setdefault(key, (file_name, []))[1].append(user)

    def image(self, key, srgb: bool, label: str, load: Callable[[], bytes],
              user: str) -> Optional[int]:
        """Index into `images` of image `key` as a colour (`srgb`) or data slot reads it, or None
        when its file is missing. Both uses of one image share its pixels (stored once)."""
        slot = (key, bool(srgb))
        if slot not in self._image_index:
            if key in self._missing:
                self.note_missing(key, self._missing[key][0], user)
                return None
            try:
                pixels = self.decoded_image(key, label, load)
            except _MissingTexture as e:
                self.note_missing(key, e.file_name, user)
                return None
            self.images.append(TextureImage(pixels, srgb, label))
            self._image_index[slot] = len(self.images) - 1
        return self._image_index[slot]

    def add_mesh(self, where: str, positions, indices, matrix=None, **attributes) -> None:
        """Validate, transform to world space with `matrix`, clean and append one mesh."""
        mesh = self._build_mesh(where, positions, indices, matrix, **attributes)
        if mesh is not None:
            self.meshes.append(mesh)

    def add_instanced(self, where: str, positions, indices, matrices, **attributes) -> None:
        """Validate and clean one mesh in its local frame; append it with its (N, 4, 4)
        object-to-world matrices."""
        matrices = np.asarray(matrices, dtype=np.float64).reshape(-1, 4, 4)
        if not np.isfinite(matrices).all():
            raise self.error(f"{where}: an instance transform is not finite (NaN or infinity)")
        mesh = self._build_mesh(where, positions, indices, None, **attributes)
        if mesh is not None:
            self.instanced.append(InstancedMesh(mesh, matrices))

    def _build_mesh(self, where: str, positions, indices, matrix=None, material: int = 0,
                    normals=None, uv0=None, uv1=None, tangents=None, colors=None,
                    name: str = "") -> Optional[TriangleMesh]:
        """The validated, transformed and cleaned mesh, or None if no triangle is left."""
        p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
        tri = np.asarray(indices).reshape(-1, 3)
        count = len(p)
        self.check_build(where, count, len(tri), material, normals is None)
        bad = int(np.count_nonzero(~np.isfinite(p).all(axis=1)))
        if bad:
            raise self.error(f"{where}: {bad} vertex positions are not finite (NaN or infinity)")
        if tri.size:
            if not np.issubdtype(tri.dtype, np.integer):
                tri = tri.astype(np.int64)
            lo, hi = int(tri.min()), int(tri.max())
            if lo < 0 or hi >= count:
                worst = lo if lo < 0 else hi
                raise self.error(f"{where}: vertex index {worst} is out of range "
                                 f"(the mesh has {count} vertices)")
        if count >= 2**31:
            raise self.error(f"{where}: {count} vertices do not fit 32-bit indices")
        tri = tri.astype(np.int64)
        attributes = {"normals": (normals, 3), "uv0": (uv0, 2), "uv1": (uv1, 2),
                      "tangents": (tangents, 4), "colors": (colors, 4)}
        arrays = {}
        for key, (value, width) in attributes.items():
            if value is None:
                arrays[key] = None
                continue
            a = np.asarray(value, dtype=np.float64)
            if a.ndim != 2 or len(a) != count or a.shape[1] != width:
                raise self.error(f"{where}: {key} have shape {a.shape}, expected ({count}, {width})")
            if key in ("uv0", "uv1", "colors"):
                bad = int(np.count_nonzero(~np.isfinite(a).all(axis=1)))
                if bad:
                    what = "texture coordinates" if key != "colors" else "vertex colours"
                    raise self.error(f"{where}: {bad} {what} are not finite (NaN or infinity)")
            arrays[key] = a

        m = np.eye(4) if matrix is None else np.asarray(matrix, dtype=np.float64)
        m3 = m[:3, :3]
        world = p @ m3.T + m[:3, 3]
        if not np.isfinite(world).all():
            raise self.error(f"{where}: vertex positions overflow under the node transform")

        # Remove degenerate triangles: repeated index, or (near-)zero area in float64.
        self.input_triangles += len(tri)
        if len(tri):
            repeated = (tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 0] == tri[:, 2])
            a, b, c = world[tri[:, 0]], world[tri[:, 1]], world[tri[:, 2]]
            twice_area = np.linalg.norm(np.cross(b - a, c - a), axis=1)
            longest_sq = np.max(np.stack([np.einsum("ij,ij->i", e, e)
                                          for e in (b - a, c - b, a - c)]), axis=0)
            flat = ~(twice_area > DEGENERATE_RELATIVE_AREA * longest_sq)
            keep = ~(repeated | flat)
            self.degenerate += int(np.count_nonzero(~keep))
            tri = tri[keep]
        if len(tri) == 0:
            return None  # nothing drawable; `finish` reports a file without any triangle

        det = float(np.linalg.det(m3))
        if det < 0.0:  # a mirroring transform: keep counter-clockwise front faces
            tri = tri[:, [0, 2, 1]]
        n = arrays["normals"]
        if n is not None:
            n = n @ normal_matrix(m3).T  # the cofactor matrix: defined for flattening transforms
            length = np.linalg.norm(n, axis=1)
            bad_rows = ~(np.isfinite(length) & (length > 1e-20))
            n = n / np.where(bad_rows, 1.0, length)[:, None]
            used = np.zeros(count, dtype=bool)
            used[tri.ravel()] = True
            repair = bad_rows & used
            if np.any(bad_rows):
                n[bad_rows] = vertex_normals(world, tri)[bad_rows]
                self.repaired_normals += int(np.count_nonzero(repair))

        uvs = [arrays["uv0"], arrays["uv1"]]
        colors = arrays["colors"]
        material_spec = self.materials[material]
        # Tangents follow the base normal map, or the clearcoat's when only that one exists.
        normal_map = material_spec.normal_texture or material_spec.clearcoat_normal_texture
        t = arrays["tangents"]
        if normal_map is not None and n is None:
            # glTF: no normals means flat shading. Split the vertices so every triangle has its
            # own flat normal, then tangents can be generated per vertex as usual.
            flat_index = tri.ravel()
            face_n = _normalize_or(np.cross(world[tri[:, 1]] - world[tri[:, 0]],
                                            world[tri[:, 2]] - world[tri[:, 0]]), np.array([0, 0, 1.0]))
            world = world[flat_index]
            n = np.repeat(face_n, 3, axis=0)
            uvs = [None if u is None else u[flat_index] for u in uvs]
            colors = None if colors is None else colors[flat_index]
            t = None  # tangents without normals have nothing to be orthogonal to
            tri = np.arange(len(flat_index)).reshape(-1, 3)
            count = len(world)

        if t is not None:
            if n is None:
                t = None
            else:
                xyz = t[:, :3] @ m3.T
                xyz = xyz - n * np.einsum("ij,ij->i", n, xyz)[:, None]
                length = np.linalg.norm(xyz, axis=1)
                ok = np.isfinite(length) & (length > 1e-20)
                w = np.where(t[:, 3] < 0.0, -1.0, 1.0) * (1.0 if det >= 0.0 else -1.0)
                xyz = xyz / np.where(ok, length, 1.0)[:, None]
                t = np.concatenate([xyz, w[:, None]], axis=1)
                if not ok.all() and normal_map is not None:
                    generated = self._tangents_for(where, world, n, uvs, tri, normal_map)
                    t[~ok] = generated[~ok]
                elif not ok.all():
                    t[~ok, :3] = _any_perpendicular(n[~ok])
        if t is None and normal_map is not None:
            t = self._tangents_for(where, world, n, uvs, tri, normal_map)

        f32 = (lambda a: None if a is None else np.ascontiguousarray(a, dtype=np.float32))
        return TriangleMesh(
            positions=f32(world),
            indices=np.ascontiguousarray(tri, dtype=np.int32),
            material=int(material),
            normals=f32(n),
            uv0=f32(uvs[0]),
            uv1=f32(uvs[1]),
            tangents=f32(t),
            colors=f32(colors),
            name=name,
        )

    def check_build(self, where: str, vertices: int, triangles: int, material: int,
                    no_normals: bool) -> None:
        """Refuse a mesh whose building (`_build_mesh`) would pass the budget: an upper bound
        from the module's constants."""
        spec = self.materials[material]
        normal_map = spec.normal_texture or spec.clearcoat_normal_texture
        split = 3 * triangles if normal_map is not None and no_normals else vertices  # flat shading
        total = split * MESH_BUILD_BYTES_PER_VERTEX + triangles * MESH_BUILD_BYTES_PER_TRIANGLE
        if normal_map is not None:
            total += split * TANGENT_BYTES_PER_VERTEX + triangles * TANGENT_BYTES_PER_TRIANGLE
        self.check_peak(f"{where} ({vertices} vertices, {triangles} triangles)", total)

    def _tangents_for(self, where, positions, normals, uvs, tri, ref: TextureRef) -> np.ndarray:
        uv = uvs[ref.uv_set]
        if uv is None:
            warnings.warn(f"{os.fspath(self.name)}: {where}: the normal map reads UV set "
                          f"{ref.uv_set}, which this mesh lacks; tangents are arbitrary",
                          MeshWarning, stacklevel=4)
            return generate_tangents(positions, normals, np.zeros((len(positions), 2)), tri)
        # Tangents follow the UVs the normal map is actually sampled with.
        m = np.asarray(ref.transform, dtype=np.float64)
        sampled = uv @ m[:2, :2].T + m[:2, 2]
        return generate_tangents(positions, normals, sampled, tri)

    def finish(self) -> MeshAsset:
        if not self.meshes and not self.instanced:
            if self.input_triangles:
                raise self.error(f"all {self.input_triangles} triangles are degenerate "
                                 "(zero area or a repeated vertex)")
            raise self.error("contains no triangles")
        if self.degenerate:
            warnings.warn(f"{os.fspath(self.name)}: skipped {self.degenerate} degenerate triangles "
                          f"of {self.input_triangles} (zero area or a repeated vertex)",
                          DegenerateTrianglesWarning, stacklevel=3)
        if self.repaired_normals:
            self.warn(f"replaced {self.repaired_normals} zero-length or non-finite normals by "
                      "averaged face normals")
        for file_name, users in self._missing.values():
            self.warn(f"texture file '{file_name}' not found; drawn without it (factors alone): "
                      + ", ".join(dict.fromkeys(users)))
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        placed = [(m, None) for m in self.meshes] + [(i.mesh, i.matrices) for i in self.instanced]
        for mesh, matrices in placed:
            referenced = np.zeros(len(mesh.positions), dtype=bool)
            referenced[mesh.indices.ravel()] = True
            box = _instance_bounds(mesh.positions[referenced].astype(np.float64), matrices)
            lo = np.minimum(lo, box[0])
            hi = np.maximum(hi, box[1])
        return MeshAsset(
            meshes=self.meshes,
            materials=self.materials,
            images=self.images,
            bounds=np.stack([lo, hi]).astype(np.float32),
            path=self.file,
            instanced=self.instanced,
            extensions_used=self.extensions_used,
            extensions_ignored=self.extensions_ignored,
        )


def _instance_bounds(points: np.ndarray, matrices: Optional[np.ndarray]) -> np.ndarray:
    """(2, 3) min / max corner of `points` (P, 3), or of their images under every matrix."""
    if matrices is None:
        return np.stack([points.min(axis=0), points.max(axis=0)])
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    chunk = max(1, (1 << 22) // max(len(points), 1))  # bounded memory for many big instances
    for start in range(0, len(matrices), chunk):
        m = matrices[start:start + chunk]
        # Every matrix row against every point in one matrix product (BLAS; an einsum here took
        # minutes for 10,000 instances of a 50,000-vertex mesh); the translation adds after the
        # extremes (rounding is monotonic, so the result is the same).
        along = (m[:, :3, :3].reshape(-1, 3) @ points.T).reshape(len(m), 3, -1)
        lo = np.minimum(lo, (along.min(axis=2) + m[:, :3, 3]).min(axis=0))
        hi = np.maximum(hi, (along.max(axis=2) + m[:, :3, 3]).max(axis=0))
    return np.stack([lo, hi])


# ---------------------------------------------------------------------------------------------
# glTF 2.0


_COMPONENT_DTYPES = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
_NORMALIZED_DIVISORS = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0, 5125: 4294967295.0}
_TYPE_SIZES = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_WRAP = {10497: "repeat", 33071: "clamp", 33648: "mirror"}
_FILTERS = {9728: "nearest", 9729: "linear", 9984: "nearest_mipmap_nearest",
            9985: "linear_mipmap_nearest", 9986: "nearest_mipmap_linear",
            9987: "linear_mipmap_linear"}
_GLB_MAGIC = 0x46546C67  # b"glTF"
_CHUNK_JSON = 0x4E4F534A
_CHUNK_BIN = 0x004E4942
_TRIANGLES, _STRIP, _FAN = 4, 5, 6


def _floats_of(values) -> tuple[float, ...]:
    return tuple(float(v) for v in values)


def _count(raw, what: str, builder: _AssetBuilder) -> int:
    """A count from the JSON: a non-negative integer (JSON booleans and fractions are not)."""
    if isinstance(raw, bool) or not isinstance(raw, (int, float)) or raw != int(raw) or raw < 0:
        raise builder.error(f"{what} {raw!r} is not a non-negative integer")
    return int(raw)


def _read_uri(builder: _AssetBuilder, uri: str, what: str) -> bytes:
    """Bytes of a data: URI or of a file relative to the model (inside its folder)."""
    if uri.startswith("data:"):
        head, _, payload = uri.partition(",")
        try:
            if head.endswith(";base64"):
                return base64.b64decode(payload, validate=False)
            return unquote(payload).encode("latin-1")
        except Exception as e:
            raise builder.error(f"{what}: bad data URI ({e})") from e
    relative = unquote(uri)
    target = builder.reference(relative, what)
    if not target.is_file():
        raise builder.error(f"{what} file '{relative}' not found")
    builder.charge_file(target, what)
    return target.read_bytes()


class _GltfReader:
    def __init__(self, builder: _AssetBuilder):
        self.b = builder
        self.doc: dict = {}
        self.bin_chunk: Optional[bytes] = None
        self._buffers: dict[int, bytes] = {}
        self._accessors: dict[int, np.ndarray] = {}
        self.skipped_primitives = 0

    # -- container ----------------------------------------------------------------------------

    def read(self) -> None:
        data = self.b.file.read_bytes()
        if self.b.file.suffix.lower() == ".glb" or data[:4] == b"glTF":
            self.doc, self.bin_chunk = self._parse_glb(data)
        else:
            try:
                self.doc = json.loads(data.decode("utf-8-sig"))
            except (UnicodeDecodeError, json.JSONDecodeError) as e:
                raise self.b.error(f"invalid glTF JSON ({e})") from e
        if not isinstance(self.doc, dict):
            raise self.b.error("invalid glTF JSON (the top level is not an object)")
        version = str(self.doc.get("asset", {}).get("version", ""))
        if not version.startswith("2"):
            raise self.b.error(f"glTF version '{version or '(missing)'}' is not supported (need 2.x)")
        unsupported = sorted(set(self.doc.get("extensionsRequired", [])) - SUPPORTED_GLTF_EXTENSIONS)
        if unsupported:
            raise self.b.error(f"requires unsupported glTF extension(s) {', '.join(unsupported)}")
        used = tuple(dict.fromkeys(str(e) for e in self.doc.get("extensionsUsed", [])))
        ignored = tuple(sorted(set(used) - SUPPORTED_GLTF_EXTENSIONS))
        self.b.extensions_used, self.b.extensions_ignored = used, ignored
        if ignored:
            self.b.warn(f"ignoring glTF extension(s) this loader does not implement: "
                        f"{', '.join(ignored)}")
        self._read_materials()
        self._read_nodes()
        if self.skipped_primitives:
            warnings.warn(f"{os.fspath(self.b.name)}: skipped {self.skipped_primitives} point or "
                          "line primitives (only triangles are rendered)", MeshWarning, stacklevel=3)

    def _parse_glb(self, data: bytes):
        if len(data) < 20:
            raise self.b.error("GLB file is truncated (shorter than its header)")
        magic, version, length = struct.unpack_from("<III", data, 0)
        if magic != _GLB_MAGIC:
            raise self.b.error("not a GLB file (bad magic number)")
        if version != 2:
            raise self.b.error(f"GLB container version {version} is not supported (need 2)")
        if length > len(data):
            raise self.b.error(f"GLB file is truncated ({len(data)} of {length} bytes)")
        offset, doc, binary = 12, None, None
        while offset + 8 <= length:
            chunk_length, chunk_type = struct.unpack_from("<II", data, offset)
            start, end = offset + 8, offset + 8 + chunk_length
            if end > length:
                raise self.b.error("GLB chunk runs past the end of the file")
            if chunk_type == _CHUNK_JSON and doc is None:
                try:
                    doc = json.loads(data[start:end].decode("utf-8"))
                except (UnicodeDecodeError, json.JSONDecodeError) as e:
                    raise self.b.error(f"invalid glTF JSON chunk ({e})") from e
            elif chunk_type == _CHUNK_BIN and binary is None:
                binary = data[start:end]
            offset = end + (-end % 4)  # chunks are 4-byte aligned
        if doc is None:
            raise self.b.error("GLB file has no JSON chunk")
        return doc, binary

    def _item(self, collection: str, index, what: str) -> dict:
        items = self.doc.get(collection, [])
        if not isinstance(index, int) or not 0 <= index < len(items):
            raise self.b.error(f"{what} refers to {collection}[{index}], which does not exist")
        return items[index]

    def _buffer(self, index: int) -> bytes:
        if index not in self._buffers:
            buf = self._item("buffers", index, "a buffer view")
            if "uri" in buf:
                data = _read_uri(self.b, buf["uri"], f"buffers[{index}]")
            elif index == 0 and self.bin_chunk is not None:
                data = self.bin_chunk
            else:
                raise self.b.error(f"buffers[{index}] has no data (no uri and no GLB binary chunk)")
            declared = int(buf.get("byteLength", len(data)))
            if len(data) < declared:
                raise self.b.error(f"buffers[{index}] holds {len(data)} bytes, fewer than its "
                                   f"byteLength {declared}")
            self._buffers[index] = data
        return self._buffers[index]

    def _view(self, index: int, what: str) -> tuple[bytes, int, int, Optional[int]]:
        """(buffer bytes, start offset, length, byteStride) of a buffer view, bounds-checked."""
        view = self._item("bufferViews", index, what)
        data = self._buffer(int(view.get("buffer", 0)))
        start = int(view.get("byteOffset", 0))
        length = int(view["byteLength"])
        if start < 0 or length < 0 or start + length > len(data):
            raise self.b.error(f"bufferViews[{index}] reaches past the end of its buffer")
        return data, start, length, view.get("byteStride")

    def _strided(self, view_index: int, offset: int, dtype: np.dtype, count: int, width: int,
                 what: str) -> np.ndarray:
        data, start, length, stride = self._view(view_index, what)
        element = dtype.itemsize * width
        stride = int(stride) if stride else element
        if stride < element:
            raise self.b.error(f"{what}: bufferViews[{view_index}] byteStride {stride} is shorter "
                               f"than one element ({element} bytes)")
        if count == 0:
            return np.zeros((0, width), dtype=dtype)
        end = offset + stride * (count - 1) + element
        if offset < 0 or end > length:
            raise self.b.error(f"{what} reads past the end of bufferViews[{view_index}]")
        raw = np.ndarray((count, width), dtype=dtype, buffer=data, offset=start + offset,
                         strides=(stride, dtype.itemsize))
        return np.array(raw)

    def accessor(self, index: int, what: str) -> np.ndarray:
        """Accessor data as an (count, components) array: float64 if float or normalized."""
        if index in self._accessors:
            return self._accessors[index]
        a = self._item("accessors", index, what)
        name = f"accessors[{index}]"
        ctype = a.get("componentType")
        if ctype not in _COMPONENT_DTYPES or a.get("type") not in _TYPE_SIZES:
            raise self.b.error(f"{name} has an unknown componentType or type")
        dtype = np.dtype(_COMPONENT_DTYPES[ctype])
        width = _TYPE_SIZES[a["type"]]
        count = _count(a.get("count", 0), f"{name} count", self.b)
        # Decoded values are float64 or int64 by the time they are used: 8 bytes per component.
        self.b.charge(f"{name} ({count} {a['type']} values)", count * width * 8)
        if "bufferView" in a:
            out = self._strided(a["bufferView"], int(a.get("byteOffset", 0)), dtype, count, width, name)
        else:  # all zeros; float ones in the float64 they end up as, without a copy
            out = np.zeros((count, width), dtype=np.float64 if ctype == 5126 else dtype)
        sparse = a.get("sparse")
        if sparse:
            n = _count(sparse["count"], f"{name} sparse count", self.b)
            if n > count:
                raise self.b.error(f"{name}: sparse count {n} is larger than the accessor's {count}")
            si, sv = sparse["indices"], sparse["values"]
            if si.get("componentType") not in (5121, 5123, 5125):
                raise self.b.error(f"{name}: bad sparse index componentType")
            where = self._strided(si["bufferView"], int(si.get("byteOffset", 0)),
                                  np.dtype(_COMPONENT_DTYPES[si["componentType"]]), n, 1,
                                  f"{name} sparse indices").ravel().astype(np.int64)
            values = self._strided(sv["bufferView"], int(sv.get("byteOffset", 0)), dtype, n, width,
                                   f"{name} sparse values")
            if n and (where.min() < 0 or where.max() >= count):
                raise self.b.error(f"{name}: sparse index out of range")
            out = out.copy()
            out[where] = values
        if a.get("normalized") and ctype in _NORMALIZED_DIVISORS:
            out = np.maximum(out.astype(np.float64) / _NORMALIZED_DIVISORS[ctype], -1.0)
        elif ctype == 5126:
            out = out.astype(np.float64)
        self._accessors[index] = out
        return out

    # -- materials and images -----------------------------------------------------------------

    def _image_bytes(self, index: int) -> Callable[[], bytes]:
        image = self._item("images", index, "a texture")

        def load() -> bytes:
            if "bufferView" in image:
                data, start, length, _ = self._view(image["bufferView"], f"images[{index}]")
                return bytes(data[start:start + length])
            if "uri" in image:
                uri = str(image["uri"])
                if uri.startswith("data:"):
                    return _read_uri(self.b, uri, f"images[{index}]")
                return _file_reader(self.b, unquote(uri), f"images[{index}]")()
            raise self.b.error(f"images[{index}] has neither a uri nor a bufferView")

        return load

    def _texture_ref(self, info: Optional[dict], srgb: bool, what: str) -> Optional[TextureRef]:
        if not info:
            return None
        texture = self._item("textures", info.get("index"), what)
        extensions = texture.get("extensions", {})
        source = extensions.get("EXT_texture_webp", {}).get("source", texture.get("source"))
        if source is None:
            raise self.b.error(f"{what}: texture {info.get('index')} has no image source this "
                               "loader can decode (KTX2/Basis and DDS are not supported)")
        image = self._item("images", source, what)
        label = f"images[{source}]"
        if "uri" in image and not str(image["uri"]).startswith("data:"):
            label += f" '{unquote(image['uri'])}'"
        elif image.get("name"):
            label += f" '{image['name']}'"
        else:
            label += f" ({image.get('mimeType', 'data URI')}, embedded)"
        image_index = self.b.image(("gltf", source), srgb, label, self._image_bytes(source), what)
        if image_index is None:
            return None  # a missing file: the slot keeps its factor alone (warned at the end)

        uv_set = int(info.get("texCoord", 0))
        transform = info.get("extensions", {}).get("KHR_texture_transform")
        matrix = np.eye(3)
        if transform is not None:
            uv_set = int(transform.get("texCoord", uv_set))
            matrix = uv_transform_matrix(transform.get("offset", (0.0, 0.0)),
                                         float(transform.get("rotation", 0.0)),
                                         transform.get("scale", (1.0, 1.0)))
        if uv_set not in (0, 1):
            raise self.b.error(f"{what} uses TEXCOORD_{uv_set}; only TEXCOORD_0 and TEXCOORD_1 "
                               "are supported")
        sampler = {}
        if "sampler" in texture:
            sampler = self._item("samplers", texture["sampler"], what)
        return TextureRef(
            texture=image_index,
            uv_set=uv_set,
            wrap_s=_WRAP.get(sampler.get("wrapS", 10497), "repeat"),
            wrap_t=_WRAP.get(sampler.get("wrapT", 10497), "repeat"),
            mag_filter=_FILTERS.get(sampler.get("magFilter")),
            min_filter=_FILTERS.get(sampler.get("minFilter")),
            transform=tuple(tuple(float(v) for v in row) for row in matrix),
        )

    def _read_materials(self) -> None:
        for i, m in enumerate(self.doc.get("materials", [])):
            name = m.get("name") or f"material {i}"
            what = f"material '{name}'"
            pbr = m.get("pbrMetallicRoughness", {})
            ext = m.get("extensions", {})
            strength = float(ext.get("KHR_materials_emissive_strength", {})
                             .get("emissiveStrength", 1.0))
            transmission = ext.get("KHR_materials_transmission", {})
            normal_info = m.get("normalTexture")

            def texture(info, srgb: bool, slot: str):
                return self._texture_ref(info, srgb, f"{what} {slot}")

            self.b.materials.append(PbrMaterial(
                name=name,
                base_color_factor=_floats_of(pbr.get("baseColorFactor", (1, 1, 1, 1))),
                metallic_factor=float(pbr.get("metallicFactor", 1.0)),
                roughness_factor=float(pbr.get("roughnessFactor", 1.0)),
                emissive_factor=tuple(float(c) * strength for c in m.get("emissiveFactor", (0, 0, 0))),
                transmission_factor=float(transmission.get("transmissionFactor", 0.0)),
                ior=float(ext.get("KHR_materials_ior", {}).get("ior", 1.5)),
                normal_scale=float((normal_info or {}).get("scale", 1.0)),
                alpha_mode=str(m.get("alphaMode", "OPAQUE")),
                alpha_cutoff=float(m.get("alphaCutoff", 0.5)),
                double_sided=bool(m.get("doubleSided", False)),
                base_color_texture=texture(pbr.get("baseColorTexture"), True, "base colour"),
                metallic_roughness_texture=texture(pbr.get("metallicRoughnessTexture"), False,
                                                   "metallic-roughness"),
                normal_texture=texture(normal_info, False, "normal map"),
                emissive_texture=texture(m.get("emissiveTexture"), True, "emissive"),
                transmission_texture=texture(transmission.get("transmissionTexture"), False,
                                             "transmission"),
                **self._clearcoat(ext.get("KHR_materials_clearcoat"), texture),
                **self._sheen(ext.get("KHR_materials_sheen"), texture),
                **self._specular(ext.get("KHR_materials_specular"), texture),
                **self._volume(ext.get("KHR_materials_volume")),
                extensions=tuple(sorted(ext)),
            ))

    # Each layer extension as PbrMaterial keyword arguments ({} when the material lacks it, so
    # the dataclass defaults, which are glTF's "no layer", apply).

    @staticmethod
    def _clearcoat(e: Optional[dict], texture) -> dict:
        if e is None:
            return {}
        normal = e.get("clearcoatNormalTexture")
        return {
            "clearcoat_factor": float(e.get("clearcoatFactor", 0.0)),
            "clearcoat_texture": texture(e.get("clearcoatTexture"), False, "clearcoat"),
            "clearcoat_roughness_factor": float(e.get("clearcoatRoughnessFactor", 0.0)),
            "clearcoat_roughness_texture": texture(e.get("clearcoatRoughnessTexture"), False,
                                                   "clearcoat roughness"),
            "clearcoat_normal_texture": texture(normal, False, "clearcoat normal map"),
            "clearcoat_normal_scale": float((normal or {}).get("scale", 1.0)),
        }

    @staticmethod
    def _sheen(e: Optional[dict], texture) -> dict:
        if e is None:
            return {}
        return {
            "sheen_color_factor": _floats_of(e.get("sheenColorFactor", (0, 0, 0))),
            "sheen_color_texture": texture(e.get("sheenColorTexture"), True, "sheen colour"),
            "sheen_roughness_factor": float(e.get("sheenRoughnessFactor", 0.0)),
            "sheen_roughness_texture": texture(e.get("sheenRoughnessTexture"), False,
                                               "sheen roughness"),
        }

    @staticmethod
    def _specular(e: Optional[dict], texture) -> dict:
        if e is None:
            return {}
        return {
            "specular_factor": float(e.get("specularFactor", 1.0)),
            "specular_texture": texture(e.get("specularTexture"), False, "specular"),
            "specular_color_factor": _floats_of(e.get("specularColorFactor", (1, 1, 1))),
            "specular_color_texture": texture(e.get("specularColorTexture"), True,
                                              "specular colour"),
        }

    @staticmethod
    def _volume(e: Optional[dict]) -> dict:
        if e is None:
            return {}
        distance = float(e.get("attenuationDistance", math.inf))
        return {
            "has_volume": True,
            "thickness_factor": float(e.get("thicknessFactor", 0.0)),
            "attenuation_color": _floats_of(e.get("attenuationColor", (1, 1, 1))),
            # glTF requires a positive distance; anything else means no absorption.
            "attenuation_distance": distance if distance > 0.0 else math.inf,
        }

    def _default_material(self) -> int:
        if not hasattr(self, "_default_index"):
            self.b.materials.append(PbrMaterial(name="default"))  # the glTF spec's default
            self._default_index = len(self.b.materials) - 1
        return self._default_index

    # -- scene graph --------------------------------------------------------------------------

    @staticmethod
    def _local_matrix(node: dict) -> np.ndarray:
        if "matrix" in node:
            return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T  # column-major
        return _trs_matrices([node.get("translation", (0, 0, 0))], [node.get("rotation", (0, 0, 0, 1))],
                             [node.get("scale", (1, 1, 1))])[0]

    def _read_nodes(self) -> None:
        nodes = self.doc.get("nodes", [])
        scenes = self.doc.get("scenes", [])
        if scenes:
            scene = self._item("scenes", self.doc.get("scene", 0), "the file")
            roots = list(scene.get("nodes", []))
        else:  # no scene: every node that is nobody's child is a root
            children = {c for n in nodes for c in n.get("children", [])}
            roots = [i for i in range(len(nodes)) if i not in children]
        stack = [(r, np.eye(4)) for r in reversed(roots)]
        placements: dict[int, list] = {}  # mesh -> (node, (k, 4, 4) matrices, gpu instancing)
        # glTF's hierarchy is a forest: a node reached twice closes a cycle or has two parents
        # (which would place its subtree once per path: exponentially many times in a few bytes).
        reached: set = set()
        while stack:
            index, parent = stack.pop()
            if index in reached:
                raise self.b.error(f"nodes[{index}] is reached twice: the node hierarchy has a cycle "
                                   "or a node with two parents (glTF requires a tree)")
            reached.add(index)
            node = self._item("nodes", index, "the scene")
            world = parent @ self._local_matrix(node)
            if "mesh" in node:
                self._item("meshes", node["mesh"], f"nodes[{index}]")
                gpu = "EXT_mesh_gpu_instancing" in node.get("extensions", {})
                matrices = self._instance_matrices(node, index, world) if gpu else world[None]
                placements.setdefault(node["mesh"], []).append((index, matrices, gpu))
            for child in reversed(node.get("children", [])):
                stack.append((child, world))
        # A mesh placed once is baked into world space; a mesh placed more often, or by
        # EXT_mesh_gpu_instancing, is kept once with its matrices (mesh_model, "Instances").
        for mesh_index, places in placements.items():
            if len(places) == 1 and not places[0][2]:
                node_index, matrices, _ = places[0]
                node = self.doc["nodes"][node_index]
                node_name = node.get("name") or f"nodes[{node_index}]"
                self._add_mesh(mesh_index, node_name, world=matrices[0])
            else:
                matrices = np.concatenate([m for _, m, _ in places])
                if len(matrices):
                    self._add_mesh(mesh_index, None, matrices=matrices)

    def _instance_matrices(self, node: dict, node_index: int, world: np.ndarray) -> np.ndarray:
        """EXT_mesh_gpu_instancing: world @ T_i @ R_i @ S_i for every instance i, (N, 4, 4)."""
        attributes = node["extensions"]["EXT_mesh_gpu_instancing"].get("attributes", {})
        where = f"nodes[{node_index}] EXT_mesh_gpu_instancing"
        columns = {}
        for key, width in (("TRANSLATION", 3), ("ROTATION", 4), ("SCALE", 3)):
            if key in attributes:
                values = self.accessor(attributes[key], where)
                if values.shape[1] != width:
                    raise self.b.error(f"{where}: {key} has {values.shape[1]} components, "
                                       f"not {width}")
                columns[key] = values.astype(np.float64)
        counts = {len(v) for v in columns.values()}
        if len(counts) > 1:
            raise self.b.error(f"{where}: TRANSLATION, ROTATION and SCALE have different counts "
                               f"({', '.join(f'{k} {len(v)}' for k, v in columns.items())})")
        n = counts.pop() if counts else 1
        local = _trs_matrices(columns.get("TRANSLATION", np.zeros((n, 3))),
                              columns.get("ROTATION", np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))),
                              columns.get("SCALE", np.ones((n, 3))))
        return world @ local

    def _add_mesh(self, mesh_index: int, node_name: Optional[str], world=None,
                  matrices=None) -> None:
        """Every primitive of a mesh: in world space with `world`, or local with `matrices`."""
        mesh = self.doc["meshes"][mesh_index]
        mesh_name = mesh.get("name") or f"meshes[{mesh_index}]"
        for p, prim in enumerate(mesh.get("primitives", [])):
            where = f"mesh '{mesh_name}' primitive {p}"
            mode = prim.get("mode", _TRIANGLES)
            if mode not in (_TRIANGLES, _STRIP, _FAN):
                self.skipped_primitives += 1
                continue
            attributes = prim.get("attributes", {})
            if "POSITION" not in attributes:
                raise self.b.error(f"{where} has no POSITION attribute")
            material = prim.get("material")
            if material is None:
                material = self._default_material()
            elif not 0 <= int(material) < len(self.doc.get("materials", [])):
                raise self.b.error(f"{where} refers to materials[{material}], which does not exist")
            # What building this primitive will take, from the declared counts, before any is read.
            vertices = self._declared_count(attributes["POSITION"], where)
            corners = self._declared_count(prim["indices"], where) if "indices" in prim else vertices
            self.b.check_build(where, vertices, corners // 3 if mode == _TRIANGLES else max(corners - 2, 0),
                               int(material), "NORMAL" not in attributes)
            positions = self.accessor(attributes["POSITION"], where)
            if positions.shape[1] != 3:
                raise self.b.error(f"{where}: POSITION is not VEC3")
            if "indices" in prim:
                flat = self.accessor(prim["indices"], where).ravel().astype(np.int64)
            else:
                flat = np.arange(len(positions), dtype=np.int64)
            tri = self._triangles(flat, mode, where)

            def optional(key: str, widths: tuple[int, ...]):
                if key not in attributes:
                    return None
                a = self.accessor(attributes[key], where)
                if a.shape[1] not in widths or len(a) != len(positions):
                    raise self.b.error(f"{where}: {key} has {len(a)}x{a.shape[1]} values for "
                                       f"{len(positions)} vertices")
                return a.astype(np.float64)

            colors = optional("COLOR_0", (3, 4))
            if colors is not None:
                colors = self._unit_colors(attributes["COLOR_0"], colors)
            data = dict(material=int(material), normals=optional("NORMAL", (3,)),
                        uv0=optional("TEXCOORD_0", (2,)), uv1=optional("TEXCOORD_1", (2,)),
                        tangents=optional("TANGENT", (4,)), colors=colors)
            if matrices is None:
                self.b.add_mesh(where, positions, tri, matrix=world,
                                name=f"{node_name}/{mesh_name}/{p}", **data)
            else:
                self.b.add_instanced(where, positions, tri, matrices, name=f"{mesh_name}/{p}", **data)

    def _declared_count(self, index, what: str) -> int:
        """The count an accessor declares (nothing read yet)."""
        return _count(self._item("accessors", index, what).get("count", 0), f"accessors[{index}] count", self.b)

    def _unit_colors(self, accessor_index: int, colors: np.ndarray) -> np.ndarray:
        """COLOR_0 as linear RGBA: glTF requires integer colours to be normalized (k / 255,
        k / 65535); a file that forgets the flag still means that. Alpha defaults to 1."""
        accessor = self.doc["accessors"][accessor_index]
        ctype = accessor.get("componentType")
        if ctype in (5121, 5123) and not accessor.get("normalized"):
            colors = colors / _NORMALIZED_DIVISORS[ctype]
        if colors.shape[1] == 3:
            colors = np.concatenate([colors, np.ones((len(colors), 1))], axis=1)
        return colors

    def _triangles(self, flat: np.ndarray, mode: int, where: str) -> np.ndarray:
        if mode == _TRIANGLES:
            if len(flat) % 3:
                raise self.b.error(f"{where}: {len(flat)} indices is not a multiple of 3")
            return flat.reshape(-1, 3)
        k = np.arange(max(len(flat) - 2, 0))
        if mode == _STRIP:  # glTF: {v_i, v_(i+1+i%2), v_(i+2-i%2)}
            return np.stack([flat[k], flat[k + 1 + k % 2], flat[k + 2 - k % 2]], axis=1)
        return np.stack([flat[k + 1], flat[k + 2], np.full_like(k, flat[0] if len(flat) else 0)],
                        axis=1)  # fan: {v_(i+1), v_(i+2), v_0}


# ---------------------------------------------------------------------------------------------
# OBJ + MTL


_MAP_OPTION_ARITY = {"-o": 3, "-s": 3, "-t": 3, "-mm": 2, "-bm": 1, "-boost": 1, "-texres": 1,
                     "-blendu": 1, "-blendv": 1, "-clamp": 1, "-cc": 1, "-imfchan": 1, "-type": 1}


def _is_number(token: str) -> bool:
    try:
        float(token)
        return True
    except ValueError:
        return False


def _parse_map_statement(args: list[str]) -> tuple[str, dict]:
    """Split `map_Kd -o 0.5 0 -s 2 2 dir/file name.png` into ('dir/file name.png', options)."""
    options: dict[str, list[str]] = {}
    i = 0
    while i < len(args) and args[i].startswith("-") and args[i].lower() in _MAP_OPTION_ARITY:
        key = args[i].lower()
        arity = _MAP_OPTION_ARITY[key]
        values = []
        i += 1
        while len(values) < arity and i < len(args) - 1:
            if key in ("-o", "-s", "-t", "-mm", "-bm", "-boost") and not _is_number(args[i]):
                break
            values.append(args[i])
            i += 1
        options[key] = values
    return " ".join(args[i:]).replace("\\", "/"), options


def _read_text(file: Path) -> str:
    return file.read_bytes().decode("utf-8", errors="replace")


def _parse_mtl(text: str) -> dict[str, dict[str, list[str]]]:
    materials: dict[str, dict[str, list[str]]] = {}
    current = None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        key, _, rest = line.replace("\t", " ").partition(" ")
        key = key.lower()
        if not (key.startswith("map") or key in ("bump", "norm", "disp", "decal", "refl")):
            rest = rest.split("#", 1)[0]  # trailing comment (file names may contain '#')
        if key == "newmtl":
            current = {}
            materials[rest.strip()] = current
        elif current is not None:
            current[key] = rest.split()
    return materials


class _MaterialNamesResolver:
    """Hands trimesh an MTL that only declares names: materials are parsed by this module."""

    def __init__(self, names: list[str]):
        self.data = "".join(f"newmtl {n}\n" for n in names).encode("utf-8")

    def get(self, key):
        return self.data

    def __getitem__(self, key):
        return self.data


def _floats(values: Optional[list[str]], n: int) -> Optional[tuple[float, ...]]:
    if not values:
        return None
    try:
        out = [float(v) for v in values[:n]]
    except ValueError:
        return None
    while len(out) < n:  # "Kd 0.5" means grey
        out.append(out[-1])
    return tuple(out)


def _obj_material(b: _AssetBuilder, name: str, entries: dict, directory: Path) -> PbrMaterial:
    kd = _floats(entries.get("kd"), 3) or (0.8, 0.8, 0.8)
    ks = _floats(entries.get("ks"), 3)
    ke = _floats(entries.get("ke"), 3)
    ns = _floats(entries.get("ns"), 1)
    ni = _floats(entries.get("ni"), 1)
    pr = _floats(entries.get("pr"), 1)
    pm = _floats(entries.get("pm"), 1)
    illum = _floats(entries.get("illum"), 1)
    d = _floats(entries.get("d"), 1)
    if d is None and entries.get("tr"):
        tr = _floats(entries.get("tr"), 1)
        d = (1.0 - tr[0],) if tr else None
    dissolve = 1.0 if d is None else min(max(d[0], 0.0), 1.0)

    if pr is not None:
        roughness = pr[0]
    elif ks is None or max(ks) <= 0.0:
        roughness = 1.0
    elif ns is not None:
        roughness = math.sqrt(math.sqrt(2.0 / (max(ns[0], 0.0) + 2.0)))
    else:
        roughness = 0.5
    base = kd
    if pm is not None:
        metallic = pm[0]
    elif max(kd) <= 0.0 and ks is not None and max(ks) > 0.0:
        metallic, base = 1.0, ks
    else:
        metallic = 0.0
    transmission, alpha = 0.0, dissolve
    if illum is not None and int(illum[0]) in (4, 6, 7, 9) and dissolve < 1.0:
        transmission, alpha = 1.0 - dissolve, 1.0
    ior = ni[0] if ni is not None and ni[0] > 1.0 else 1.5

    def texture(key: str, srgb: bool) -> Optional[TextureRef]:
        args = entries.get(key)
        if not args:
            return None
        file_name, options = _parse_map_statement(args)
        if not file_name:
            return None
        what = f"material '{name}' {key}"
        target = b.reference(file_name, what, directory)
        offset = _floats(options.get("-o"), 2) or (0.0, 0.0)
        scale = _floats(options.get("-s"), 2) or (1.0, 1.0)
        # MTL -o/-s act on v-up coordinates; in the stored v-down frame v' = s v + (1 - s - o).
        matrix = ((scale[0], 0.0, offset[0]), (0.0, scale[1], 1.0 - scale[1] - offset[1]),
                  (0.0, 0.0, 1.0))
        wrap = "clamp" if options.get("-clamp", ["off"])[0].lower() == "on" else "repeat"
        index = b.image(("file", str(target)), srgb, f"'{file_name}'",
                        _file_reader(b, file_name, what, directory), what)
        if index is None:
            return None  # missing: the material keeps its factors (warned at the end)
        return TextureRef(texture=index, uv_set=0, wrap_s=wrap, wrap_t=wrap,
                          transform=tuple(tuple(float(v) for v in row) for row in matrix))

    normal = texture("norm", False)
    normal_scale = 1.0
    if normal is None:
        for key in ("map_bump", "bump"):
            if entries.get(key):
                file_name, options = _parse_map_statement(entries[key])
                what = f"material '{name}' {key}"
                image_key = ("file", str(b.reference(file_name, what, directory)))
                try:
                    raw = b.decoded_image(image_key, f"'{file_name}'",
                                          _file_reader(b, file_name, what, directory))
                except _MissingTexture:
                    b.note_missing(image_key, file_name, f"material '{name}' {key}")
                    break
                mean = _unit_values(raw[:, :, :3]).reshape(-1, 3).mean(axis=0)
                if mean[2] > 0.6 and abs(mean[0] - 0.5) < 0.2 and abs(mean[1] - 0.5) < 0.2:
                    normal = texture(key, False)
                    bm = _floats(options.get("-bm"), 1)
                    normal_scale = 1.0 if bm is None else bm[0]
                else:
                    b.warn(f"material '{name}': height-map bump '{file_name}' ignored (only "
                           "normal maps are supported)")
                break
    emissive_texture = texture("map_ke", True)
    emission = ke if ke is not None else ((1.0, 1.0, 1.0) if emissive_texture else (0.0, 0.0, 0.0))
    return PbrMaterial(
        name=name,
        base_color_factor=(*(float(c) for c in base), float(alpha)),
        metallic_factor=float(min(max(metallic, 0.0), 1.0)),
        roughness_factor=float(min(max(roughness, 0.0), 1.0)),
        emissive_factor=tuple(float(c) for c in emission),
        transmission_factor=float(transmission),
        ior=float(ior),
        normal_scale=float(normal_scale),
        alpha_mode="BLEND" if alpha < 1.0 else "OPAQUE",
        base_color_texture=texture("map_kd", True),
        normal_texture=normal,
        emissive_texture=emissive_texture,
    )


def _fan_triangulate(faces) -> np.ndarray:
    """(F, k) polygons (trimesh leaves all-quad groups as quads) as (T, 3) triangle fans."""
    if isinstance(faces, np.ndarray) and faces.ndim == 2 and faces.dtype != object:
        k = faces.shape[1]
        if k == 3:
            return faces
        if k < 3:
            raise ValueError(f"faces with {k} vertices")
        return np.concatenate([faces[:, [0, i, i + 1]] for i in range(1, k - 1)], axis=0)
    triangles = [[f[0], f[i], f[i + 1]] for f in faces for i in range(1, len(f) - 1)]
    return np.asarray(triangles, dtype=np.int64).reshape(-1, 3)


def _default_grey(b: _AssetBuilder, vertex_colors: bool = False) -> int:
    """The material of formats without materials (and of OBJ faces without one)."""
    b.materials.append(PbrMaterial(
        name="default",
        base_color_factor=(1.0, 1.0, 1.0, 1.0) if vertex_colors else (0.8, 0.8, 0.8, 1.0),
        metallic_factor=0.0,
        roughness_factor=0.5,
    ))
    return len(b.materials) - 1


def _load_obj(b: _AssetBuilder) -> None:
    from trimesh.exchange.obj import load_obj

    text = _read_text(b.file)
    b.check_peak("parsing the OBJ file", b.file.stat().st_size * TRIMESH_PARSE_BYTES_PER_BYTE)
    libraries = []
    for match in re.finditer(r"^[ \t]*mtllib[ \t]+(.+?)[ \t]*$", text, flags=re.MULTILINE):
        value = match.group(1).replace("\\", "/")
        whole = b.file.parent / value
        libraries.extend([value] if whole.is_file() else value.split())
    mtl: dict[str, dict] = {}
    for library in libraries:
        target = b.reference(library, "material library")
        if not target.is_file():
            raise b.error(f"material library '{library}' not found")
        b.charge_file(target, "material library")
        for name, entries in _parse_mtl(_read_text(target)).items():
            mtl.setdefault(name, (entries, target.parent))
    index = {}
    for name, (entries, directory) in mtl.items():
        b.materials.append(_obj_material(b, name, entries, directory))
        index[name] = len(b.materials) - 1

    with open(b.file, "rb") as f:
        try:
            kwargs = load_obj(f, resolver=_MaterialNamesResolver(list(mtl)), group_material=True)
        except IndexError as e:  # trimesh indexes its vertex arrays with the face indices
            raise b.error("a face refers to a vertex that does not exist "
                          "(vertex index out of range)") from e
    geometry = kwargs.get("geometry", {})
    default = None
    for key in sorted(geometry, key=str):
        g = geometry[key]
        faces = g.get("faces")
        if faces is None or len(faces) == 0:
            continue
        faces = _fan_triangulate(faces)
        visual = g.get("visual")
        material_name = getattr(getattr(visual, "material", None), "name", None)
        if material_name in index:
            material = index[material_name]
        else:
            if default is None:
                default = _default_grey(b)
            material = default
        uv = getattr(visual, "uv", None)
        if uv is not None:
            uv = np.asarray(uv, dtype=np.float64)[:, :2].copy()
            if len(uv) != len(g["vertices"]):
                uv = None
            else:
                uv[:, 1] = 1.0 - uv[:, 1]  # OBJ is v-up
        colors = _color_array(g.get("vertex_colors"), len(g["vertices"]))
        where = f"material '{material_name}'" if material_name in index else "faces without a material"
        b.add_mesh(where, g["vertices"], faces, material=material,
                   normals=g.get("vertex_normals"), uv0=uv, colors=colors, name=str(key))


# ---------------------------------------------------------------------------------------------
# PLY and STL


def _ply_texture_file(file: Path) -> Optional[str]:
    with open(file, "rb") as f:
        header = b""
        while b"end_header" not in header and len(header) < 1 << 20:
            line = f.readline()
            if not line:
                break
            header += line
    match = re.search(rb"^comment\s+TextureFile\s+(.+?)\s*$", header, flags=re.MULTILINE)
    return match.group(1).decode("utf-8", errors="replace") if match else None


def _color_array(values, count: int) -> Optional[np.ndarray]:
    if values is None:
        return None
    c = np.asarray(values)
    if c.ndim != 2 or len(c) != count or c.shape[1] not in (3, 4):
        return None
    if np.issubdtype(c.dtype, np.integer):
        c = c.astype(np.float64) / float(np.iinfo(c.dtype).max)
    c = np.clip(c.astype(np.float64), 0.0, 1.0)
    if c.shape[1] == 3:
        c = np.concatenate([c, np.ones((count, 1))], axis=1)
    c[:, :3] = srgb_to_linear(c[:, :3])
    return c


def _load_ply(b: _AssetBuilder) -> None:
    from trimesh.exchange.ply import load_ply

    b.check_peak("parsing the PLY file", b.file.stat().st_size * TRIMESH_PARSE_BYTES_PER_BYTE)
    with open(b.file, "rb") as f:
        kwargs = load_ply(f, fix_texture=True, skip_materials=True)
    faces = kwargs.get("faces")
    vertices = kwargs.get("vertices")
    if faces is None or vertices is None or len(faces) == 0:
        raise b.error("contains no triangles")
    faces = np.asarray(faces)
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise b.error("faces are not triangles after triangulation")
    colors = _color_array(kwargs.get("vertex_colors"), len(vertices))
    material = _default_grey(b, vertex_colors=colors is not None)
    uv = getattr(kwargs.get("visual"), "uv", None)
    if uv is not None:
        uv = np.asarray(uv, dtype=np.float64)[:, :2].copy()
        uv[:, 1] = 1.0 - uv[:, 1]  # PLY texture coordinates are v-up, as OBJ
        texture_file = _ply_texture_file(b.file)
        if texture_file:
            what = "TextureFile"
            index = b.image(("file", str(b.reference(texture_file, what))), True, f"'{texture_file}'",
                            _file_reader(b, texture_file, what), "base colour")
            if index is not None:
                b.materials[material] = dataclasses.replace(
                    b.materials[material], base_color_texture=TextureRef(texture=index),
                    base_color_factor=(1.0, 1.0, 1.0, 1.0))
    b.add_mesh("mesh", vertices, faces, material=material, normals=kwargs.get("vertex_normals"),
               uv0=uv, colors=colors, name=b.file.stem)


def _load_stl(b: _AssetBuilder) -> None:
    from trimesh.exchange.stl import load_stl

    size = b.file.stat().st_size
    with open(b.file, "rb") as f:
        head = f.read(84)
    if len(head) == 84 and not head.startswith(b"solid"):  # binary: 84-byte header, 50 bytes a triangle
        declared = struct.unpack_from("<I", head, 80)[0]
        if size != 84 + 50 * declared:
            raise b.error(f"binary STL declares {declared} triangles ({84 + 50 * declared} bytes) "
                          f"but the file holds {size} bytes (truncated or damaged)")
    b.check_peak("parsing the STL file", size * TRIMESH_PARSE_BYTES_PER_BYTE)
    with open(b.file, "rb") as f:
        kwargs = load_stl(f)
    faces = kwargs.get("faces")
    if faces is None or len(faces) == 0:
        raise b.error("contains no triangles")
    b.add_mesh("mesh", kwargs["vertices"], faces, material=_default_grey(b), name=b.file.stem)

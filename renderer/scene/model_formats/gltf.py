"""glTF 2.0 and GLB files.

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
"""
from __future__ import annotations

import base64
import json
import math
import os
import struct
import warnings
from typing import Callable, Optional
from urllib.parse import unquote

import numpy as np

from renderer.scene.mesh_model import PbrMaterial, TextureRef, uv_transform_matrix
from renderer.scene.model_formats.builder import AssetBuilder, file_reader
from renderer.scene.model_formats.mesh_warnings import MeshWarning

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


def _count(raw, what: str, builder: AssetBuilder) -> int:
    """A count from the JSON: a non-negative integer (JSON booleans and fractions are not)."""
    if isinstance(raw, bool) or not isinstance(raw, (int, float)) or raw != int(raw) or raw < 0:
        raise builder.error(f"{what} {raw!r} is not a non-negative integer")
    return int(raw)


def _read_uri(builder: AssetBuilder, uri: str, what: str) -> bytes:
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


class GltfReader:
    def __init__(self, builder: AssetBuilder):
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
                return file_reader(self.b, unquote(uri), f"images[{index}]")()
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
            self.b.materials.append(PbrMaterial(name="default", double_sided=False))  # the glTF spec's default
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

"""What every model format shares: materials, images, validation, placement and bounds of meshes.

A reader (gltf, obj_mtl, ply_stl) hands an `AssetBuilder` its materials, images and meshes; the
builder checks them against the memory budget, validates and cleans every mesh (module notes of
the package: "Checks"), places world meshes with their node transform (by mesh_model's
`placed_points` and `placed_normals`, as `place_mesh` does) and returns the `MeshAsset`.
"""
from __future__ import annotations

import os
import re
import warnings
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from renderer.scene.errors import PathLike, SceneError
from renderer.scene.limits import MemoryLedger
from renderer.scene.load_options import LoadOptions
from renderer.scene.mesh_model import (
    InstancedMesh,
    MeshAsset,
    PbrMaterial,
    TextureImage,
    TextureRef,
    TriangleMesh,
    as_float32,
    placed_normals,
    placed_points,
)
from renderer.scene.model_formats.image_decoding import DECODE_PEAK, DECODED, IMAGE_COPIES, decode_image, image_header
from renderer.scene.model_formats.mesh_warnings import DegenerateTrianglesWarning, MeshWarning
from renderer.scene.model_formats.normals import normalize_or, vertex_normals
from renderer.scene.model_formats.tangents import any_perpendicular, generate_tangents
from renderer.scene.references import resolve_reference
from renderer.scene.srgb import srgb_to_linear

DEGENERATE_RELATIVE_AREA = 1e-12  # see the package notes ("Checks")

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


class MissingTexture(Exception):
    """A texture file that is not there, or is there but not an image the decoders read (the
    loader warns and goes on without it); `reason` says which."""

    def __init__(self, file_name: str, reason: str = "not found"):
        super().__init__(file_name, reason)
        self.file_name = file_name
        self.reason = reason


def decode_failure(error: Exception) -> str:
    """Why an image did not decode, in words: never a library object's repr."""
    if type(error).__name__ == "UnidentifiedImageError":
        return "not an image format the decoders read"
    text = re.sub(r"<[^<>]* at 0x[0-9a-fA-F]+>", "the data", str(error)).strip()
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def file_reader(builder: "AssetBuilder", reference: str, what: str,
                base: Optional[Path] = None) -> Callable[[], bytes]:
    """Reads a texture file the model names as `reference`, or raises MissingTexture(reference)
    if it does not exist; a reference outside the model's folder is refused (SceneError)."""

    def load() -> bytes:
        target = builder.reference(reference, what, base)
        if not target.is_file():
            raise MissingTexture(reference)
        builder.check_peak(f"{what} '{reference}'", target.stat().st_size)
        return target.read_bytes()

    return load


class AssetBuilder:
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
        Raises MissingTexture when its file is missing."""
        if key not in self._decoded:
            data = load()
            try:
                width, height, decoding = image_header(data)
            except Exception as e:  # Pillow raises many types for bad data
                raise MissingTexture(label, f"cannot be decoded ({decode_failure(e)})") from None
            pixels = width * height
            self.charge(f"image {label} ({width}x{height})", pixels * DECODED[decoding] * IMAGE_COPIES)
            self.check_peak(f"decoding image {label} ({width}x{height})",
                            pixels * DECODE_PEAK[decoding] + len(data))
            try:
                self._decoded[key] = decode_image(data)
            except Exception as e:  # Pillow raises many types for bad data
                raise MissingTexture(label, f"cannot be decoded ({decode_failure(e)})") from None
        return self._decoded[key]

    def note_missing(self, key, file_name: str, user: str, reason: str = "not found") -> None:
        """Remember that `user` (e.g. "material 'wood' base colour") wanted a file that is
        missing or does not decode (`reason`)."""
        self._missing.setdefault(key, (file_name, reason, []))[2].append(user)

    def image(self, key, srgb: bool, label: str, load: Callable[[], bytes],
              user: str) -> Optional[int]:
        """Index into `images` of image `key` as a colour (`srgb`) or data slot reads it, or None
        when its file is missing. Both uses of one image share its pixels (stored once)."""
        slot = (key, bool(srgb))
        if slot not in self._image_index:
            if key in self._missing:
                file_name, reason, _ = self._missing[key]
                self.note_missing(key, file_name, user, reason)
                return None
            try:
                pixels = self.decoded_image(key, label, load)
            except MissingTexture as e:
                self.note_missing(key, e.file_name, user, e.reason)
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
        world = placed_points(p, m)
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
            n = placed_normals(n, m3)  # the cofactor matrix: defined for flattening transforms
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
            face_n = normalize_or(np.cross(world[tri[:, 1]] - world[tri[:, 0]],
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
                    t[~ok, :3] = any_perpendicular(n[~ok])
        if t is None and normal_map is not None:
            t = self._tangents_for(where, world, n, uvs, tri, normal_map)

        return TriangleMesh(
            positions=as_float32(world),
            indices=np.ascontiguousarray(tri, dtype=np.int32),
            material=int(material),
            normals=as_float32(n),
            uv0=as_float32(uvs[0]),
            uv1=as_float32(uvs[1]),
            tangents=as_float32(t),
            colors=as_float32(colors),
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
        for file_name, reason, users in self._missing.values():
            what = f"texture file '{file_name}' not found" if reason == "not found" else f"texture {file_name} {reason}"
            self.warn(f"{what}; drawn without it (factors alone): " + ", ".join(dict.fromkeys(users)))
        lo = np.full(3, np.inf)
        hi = np.full(3, -np.inf)
        placed = [(m, None) for m in self.meshes] + [(i.mesh, i.matrices) for i in self.instanced]
        for mesh, matrices in placed:
            referenced = np.zeros(len(mesh.positions), dtype=bool)
            referenced[mesh.indices.ravel()] = True
            box = instance_bounds(mesh.positions[referenced].astype(np.float64), matrices)
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


def instance_bounds(points: np.ndarray, matrices: Optional[np.ndarray]) -> np.ndarray:
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


def default_grey(b: AssetBuilder, vertex_colors: bool = False) -> int:
    """The material of formats without materials (and of OBJ faces without one)."""
    b.materials.append(PbrMaterial(
        name="default",
        base_color_factor=(1.0, 1.0, 1.0, 1.0) if vertex_colors else (0.8, 0.8, 0.8, 1.0),
        metallic_factor=0.0,
        roughness_factor=0.5,
    ))
    return len(b.materials) - 1


def linear_vertex_colors(values, count: int) -> Optional[np.ndarray]:
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

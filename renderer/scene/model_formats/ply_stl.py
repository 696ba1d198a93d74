"""PLY and STL files: geometry without materials.

Geometry through trimesh (`load_ply` / `load_stl`). One grey material (base 0.8, metallic 0,
roughness 0.5, as the TOML scene defaults). PLY vertex colours are kept as
`TriangleMesh.colors`, decoded as sRGB (they are display-referred in every writer we know),
and the material's base colour is then white so that the colours show unchanged. Face colours
are ignored. A PLY `comment TextureFile` image with per-vertex or per-face UVs becomes the
base colour texture.
"""
from __future__ import annotations

import dataclasses
import re
import struct
from pathlib import Path
from typing import Optional

import numpy as np

from renderer.scene.mesh_model import TextureRef
from renderer.scene.model_formats.builder import (
    TRIMESH_PARSE_BYTES_PER_BYTE,
    AssetBuilder,
    default_grey,
    file_reader,
    linear_vertex_colors,
)


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


def read_ply(b: AssetBuilder) -> None:
    from trimesh.exchange.ply import load_ply

    b.check_peak("parsing the PLY file", b.file.stat().st_size * TRIMESH_PARSE_BYTES_PER_BYTE)

    def parsed(fix_texture: bool) -> dict:
        with open(b.file, "rb") as f:
            return load_ply(f, fix_texture=fix_texture, skip_materials=True)

    # Per-vertex attributes as the file has them. trimesh's fix_texture re-indexes vertices for
    # texture coordinates given per face; for per-vertex ones it merges vertices that differ only
    # in their normals and keeps the normals unmerged (a hard edge lost, the arrays out of step), so
    # it is used only where the file's coordinates are per face.
    kwargs = parsed(False)
    uv = getattr(kwargs.get("visual"), "uv", None)
    if uv is not None and len(uv) != len(kwargs.get("vertices", ())):
        kwargs = parsed(True)
    faces = kwargs.get("faces")
    vertices = kwargs.get("vertices")
    if faces is None or vertices is None or len(faces) == 0:
        raise b.error("contains no triangles")
    faces = np.asarray(faces)
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise b.error("faces are not triangles after triangulation")
    colors = linear_vertex_colors(kwargs.get("vertex_colors"), len(vertices))
    material = default_grey(b, vertex_colors=colors is not None)
    uv = getattr(kwargs.get("visual"), "uv", None)
    if uv is not None:
        uv = np.asarray(uv, dtype=np.float64)[:, :2].copy()
        uv[:, 1] = 1.0 - uv[:, 1]  # PLY texture coordinates are v-up, as OBJ
        texture_file = _ply_texture_file(b.file)
        if texture_file:
            what = "TextureFile"
            index = b.image(("file", str(b.reference(texture_file, what))), True, f"'{texture_file}'",
                            file_reader(b, texture_file, what), "base colour")
            if index is not None:
                b.materials[material] = dataclasses.replace(
                    b.materials[material], base_color_texture=TextureRef(texture=index),
                    base_color_factor=(1.0, 1.0, 1.0, 1.0))
    normals = kwargs.get("vertex_normals")
    if normals is not None and len(normals) != len(vertices):  # re-indexed above: the file's normals no longer fit
        normals = None
    b.add_mesh("mesh", vertices, faces, material=material, normals=normals, uv0=uv, colors=colors, name=b.file.stem)


def read_stl(b: AssetBuilder) -> None:
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
    b.add_mesh("mesh", kwargs["vertices"], faces, material=default_grey(b), name=b.file.stem)

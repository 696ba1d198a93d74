"""What the model-file tests share: where the test data lies, independent references (TRS matrices,
geometric normals, texel values), a one-line error's check and a minimal glTF writer."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from renderer.scene.model_formats.gltf_writing import BufferBuilder, data_uri_buffer
from renderer.scene.srgb import srgb_to_linear
from renderer.scene.textures import as_rgba

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"
MODELS = REPO / "assets" / "models"


def rgba(pixels: np.ndarray, srgb: bool) -> np.ndarray:
    """What a lookup should read for 8-bit pixels: k / 255, sRGB-decoded if a colour slot."""
    values = pixels.astype(np.float64) / 255.0
    if srgb:
        values = srgb_to_linear(values)
    return as_rgba(values)


def geometric_normals(positions: np.ndarray, indices: np.ndarray) -> np.ndarray:
    p = positions.astype(np.float64)
    n = np.cross(p[indices[:, 1]] - p[indices[:, 0]], p[indices[:, 2]] - p[indices[:, 0]])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def trs(translation=(0, 0, 0), rotation_y_deg=0.0, scale=(1, 1, 1)) -> np.ndarray:
    """Independent TRS matrix (rotation about +y only: that is all the test files use)."""
    a = math.radians(rotation_y_deg)
    r = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
    m = np.eye(4)
    m[:3, :3] = r @ np.diag(scale)
    m[:3, 3] = translation
    return m


def one_line_error(excinfo, path) -> str:
    message = str(excinfo.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: "), message
    return message


def write_gltf(path: Path, positions, indices, extra_doc=None) -> Path:
    b = BufferBuilder()
    # no min / max: they would hold NaN for the bad-input cases
    position_accessor = b.accessor(np.asarray(positions, dtype=np.float32), bounds=False)
    index_accessor = b.accessor(np.asarray(indices, dtype=np.uint16))
    doc = {
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"name": "m", "primitives": [
            {"attributes": {"POSITION": position_accessor}, "indices": index_accessor}]}],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": data_uri_buffer(b),
    }
    doc.update(extra_doc or {})
    path.write_text(json.dumps(doc))
    return path


TRIANGLE = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]


# A unit quad in the z = 0 plane, counter-clockwise seen from +z: its front faces +z.
UNIT_QUAD = np.array([[-0.5, -0.5, 0.0], [0.5, -0.5, 0.0], [0.5, 0.5, 0.0], [-0.5, 0.5, 0.0]], np.float32)
UNIT_QUAD_INDICES = np.array([0, 1, 2, 0, 2, 3], np.uint16)


def write_quads_gltf(path: Path, placements, normals=True) -> Path:
    """A glTF file of unit quads (UNIT_QUAD, vertex normals +z unless not `normals`: then the
    winding alone says which side is the front), black and rough: one node per
    placement (name, translation, scale, parent_scale, double_sided, shared). parent_scale (or
    None) puts the node under a parent that holds the translation and that scale; the quads of
    `shared` placements are one mesh placed by several nodes (the loader instances it), each other
    quad a mesh of its own (the loader places it in the world)."""
    b = BufferBuilder()
    attributes = {"POSITION": b.accessor(UNIT_QUAD)}
    if normals:
        attributes["NORMAL"] = b.accessor(np.tile(np.float32([0.0, 0.0, 1.0]), (4, 1)))
    indices = b.accessor(UNIT_QUAD_INDICES)
    black = {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}
    materials = [{"name": "single", "doubleSided": False, "pbrMetallicRoughness": black},
                 {"name": "double", "doubleSided": True, "pbrMetallicRoughness": black}]
    meshes, nodes, roots, shared_mesh = [], [], [], {}
    for name, translation, scale, parent_scale, double_sided, shared in placements:
        key = (shared, double_sided)
        if not shared or key not in shared_mesh:
            meshes.append({"name": name, "primitives": [{"attributes": attributes, "indices": indices,
                                                         "material": int(double_sided)}]})
            shared_mesh[key] = len(meshes) - 1
        node = {"name": name, "mesh": shared_mesh[key] if shared else len(meshes) - 1, "scale": list(scale)}
        if parent_scale is None:
            node["translation"] = list(translation)
            nodes.append(node)
        else:
            nodes.append(node)
            nodes.append({"name": f"{name}_parent", "translation": list(translation), "scale": list(parent_scale),
                          "children": [len(nodes) - 1]})
        roots.append(len(nodes) - 1)
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": roots}], "nodes": nodes, "meshes": meshes,
           "materials": materials, "accessors": b.accessors, "bufferViews": b.views, "buffers": data_uri_buffer(b)}
    path.write_text(json.dumps(doc))
    return path

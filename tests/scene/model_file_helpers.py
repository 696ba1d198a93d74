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

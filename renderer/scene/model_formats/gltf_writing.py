"""glTF files written by the project's own model generators (scripts/make_textured_gltf.py,
tests/data/make_test_models.py and the tests' small models): one binary buffer of 4-byte aligned
views and their accessors, the buffer as a data URI, PNG images and the GLB container."""
from __future__ import annotations

import base64
import io
import json
import struct

import numpy as np

ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
GLB_MAGIC, GLB_VERSION = 0x46546C67, 2  # b"glTF"
CHUNK_JSON, CHUNK_BIN = 0x4E4F534A, 0x004E4942  # b"JSON", b"BIN\0"
COMPONENT_TYPES = {np.dtype(np.float32): 5126, np.dtype(np.uint8): 5121, np.dtype(np.int16): 5122,
                   np.dtype(np.uint16): 5123, np.dtype(np.uint32): 5125}
ACCESSOR_TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}


class BufferBuilder:
    """Accumulates binary data into one glTF buffer with 4-byte aligned buffer views."""

    def __init__(self):
        self.data = bytearray()
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def view(self, blob: bytes, target: int | None = None) -> int:
        self.data += b"\0" * (-len(self.data) % 4)
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(blob)}
        if target is not None:
            view["target"] = target
        self.data += blob
        self.views.append(view)
        return len(self.views) - 1

    def accessor(self, array: np.ndarray, normalized: bool = False, sparse: dict | None = None,
                 with_view: bool = True, bounds: bool | None = None) -> int:
        """An accessor over `array`: 1-D arrays are indices (SCALAR, an element-array view),
        (N, k) arrays vertex attributes. `bounds`: write min / max (POSITION needs them); None
        writes them for float VEC3 data."""
        array = np.ascontiguousarray(array)
        component = COMPONENT_TYPES[array.dtype]
        kind = ACCESSOR_TYPES[1 if array.ndim == 1 else array.shape[1]]
        index_data = array.ndim == 1
        accessor = {"componentType": component, "count": int(len(array)), "type": kind}
        if with_view:
            accessor["bufferView"] = self.view(array.tobytes(), ELEMENT_ARRAY_BUFFER if index_data else ARRAY_BUFFER)
        if normalized:
            accessor["normalized"] = True
        if bounds or (bounds is None and kind == "VEC3" and component == 5126):
            accessor["min"] = [float(v) for v in array.min(axis=0)]
            accessor["max"] = [float(v) for v in array.max(axis=0)]
        if sparse:
            accessor["sparse"] = sparse
        self.accessors.append(accessor)
        return len(self.accessors) - 1


def data_uri_buffer(b: BufferBuilder) -> list[dict]:
    """The glTF `buffers` list holding `b`'s data as an embedded base64 data URI."""
    return [{"byteLength": len(b.data), "uri": "data:application/octet-stream;base64,"
             + base64.b64encode(bytes(b.data)).decode("ascii")}]


def png_bytes(pixels: np.ndarray, optimize: bool = False) -> bytes:
    from PIL import Image

    out = io.BytesIO()
    Image.fromarray(pixels).save(out, format="PNG", optimize=optimize)
    return out.getvalue()


def png16_bytes(pixels: np.ndarray) -> bytes:
    """A 16-bit-per-channel RGB PNG (Pillow writes only 8-bit colour PNGs; OpenCV writes these)."""
    import cv2

    ok, data = cv2.imencode(".png", np.ascontiguousarray(pixels[:, :, ::-1]))  # OpenCV is BGR
    assert ok
    return data.tobytes()


def glb_bytes(doc: dict, binary: bytes) -> bytes:
    """The GLB container: header, JSON chunk (space padded), BIN chunk (zero padded)."""
    text = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    length = 12 + 8 + len(text) + 8 + len(binary)
    return (struct.pack("<III", GLB_MAGIC, GLB_VERSION, length)
            + struct.pack("<II", len(text), CHUNK_JSON) + text
            + struct.pack("<II", len(binary), CHUNK_BIN) + binary)

"""Texture images decoded at their own precision (8-bit, 16-bit, float), and their size and decoding
cost read from the header alone, before anything is decoded (the memory budget decides first)."""
from __future__ import annotations

import io
import struct
import warnings

import numpy as np


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
DECODE_PEAK = {"png16": 48, "grey16": 30, "float": 24, "8bit": 12}
DECODED = {"png16": 8, "grey16": 8, "float": 16, "8bit": 4}
# A decoded image lives on in the scene's texture atlas and in the device's copy of that atlas, each
# a third larger with its mip levels (renderer/scene/texture_mips.py), whose making takes about
# one more copy for a moment: four copies in all.
IMAGE_COPIES = 4


def _is_16_bit_png(data: bytes) -> bool:
    # PNG signature, then the IHDR chunk: bit depth is byte 24 of the file.
    return data[:8] == _PNG_SIGNATURE and len(data) > 25 and data[24] == 16


def image_header(data: bytes) -> tuple[int, int, str]:
    """(width, height, decoding) from an image's header alone, before anything is decoded;
    decoding is a key of DECODED."""
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


def decode_image(data: bytes) -> np.ndarray:
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


def unit_values(pixels: np.ndarray) -> np.ndarray:
    """Stored texels as float64 in [0, 1] (8-bit ones as k / 255), undecoded."""
    return pixels / 255.0 if pixels.dtype == np.uint8 else pixels.astype(np.float64)

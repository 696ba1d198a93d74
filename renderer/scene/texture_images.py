"""The images of a scene description's texture specs (`TextureSpec`): an image file read and
decoded, or a checkerboard made as the 2x2 image it is under nearest filtering.

Image files are charged to the scene's memory budget before they are decoded, as model files'
images are; a file that is missing or does not decode is one SceneError naming it (the scene
file asked for it by name, so drawing without it would be a silently wrong image).
"""
from __future__ import annotations

import os

import numpy as np

from renderer.scene.description import TextureSpec
from renderer.scene.errors import SceneError
from renderer.scene.limits import MemoryLedger
from renderer.scene.mesh_model import TextureImage
from renderer.scene.model_formats.builder import decode_failure
from renderer.scene.model_formats.image_decoding import DECODE_PEAK, DECODED, IMAGE_COPIES, decode_image, image_header
from renderer.scene.references import missing_file_problem
from renderer.scene.texture_mixing import mixed_image



def texture_image(spec: TextureSpec, ledger: MemoryLedger) -> TextureImage:
    if spec.kind == "checkerboard":
        return checkerboard_image(spec.color0, spec.color1)
    if spec.kind in ("mix", "product"):
        return mixed_image(spec, ledger, texture_image)
    if spec.kind != "bitmap":
        raise ValueError(f"unknown texture kind '{spec.kind}'")
    return _bitmap(spec, ledger)


def checkerboard_image(color0, color1) -> TextureImage:
    """2x2 texels, row 0 on top: color0 where u and v are both below or both above 1/2. Read with
    nearest filtering and repeat wrapping it is the checkerboard exactly."""
    c0 = (*map(float, color0), 1.0)
    c1 = (*map(float, color1), 1.0)
    pixels = np.array([[c0, c1], [c1, c0]], np.float32)
    return TextureImage(pixels, srgb=False, label="checkerboard")


def _bitmap(spec: TextureSpec, ledger: MemoryLedger) -> TextureImage:
    path = spec.file
    if path is None or not path.is_file():
        raise SceneError(path or "<texture>", f"texture image {missing_file_problem(path) if path else 'not given'}")
    label = path.name
    if path.suffix.lower() == ".exr":  # linear floats: never sRGB-decoded
        from renderer.output.image_io import read_exr

        rgb = read_exr(path, ledger.budget)  # refused by its header's size beyond the budget
        pixels = np.concatenate([rgb, np.ones(rgb.shape[:2] + (1,), np.float32)], axis=-1)
        ledger.charge(path, f"texture {label}", pixels.nbytes * IMAGE_COPIES)
        return TextureImage(np.ascontiguousarray(pixels, np.float32), srgb=False, label=label)
    data = path.read_bytes()
    try:
        width, height, decoding = image_header(data)
        pixel_count = width * height
        ledger.charge(path, f"texture {label} ({width}x{height})", pixel_count * DECODED[decoding] * IMAGE_COPIES)
        ledger.check_peak(path, f"decoding texture {label}", pixel_count * DECODE_PEAK[decoding] + len(data))
        pixels = decode_image(data)
    except SceneError:
        raise
    except Exception as error:  # Pillow raises many types for bad data
        raise SceneError(path, f"cannot be decoded as a texture ({decode_failure(error)})") from None
    return TextureImage(pixels, srgb=spec.srgb, label=os.fspath(label))

"""Reading environment maps and writing rendered images.

All images cross this module as numpy arrays of shape (height, width, 3) with row 0 at the top.
Environment maps are equirectangular, so row 0 is the zenith (+y). Values are linear Rec.709 RGB
except for PNG, which holds display-referred values.
"""
from __future__ import annotations

import math
import os
import re
import warnings
from pathlib import Path
from typing import Optional

import numpy as np

from renderer.output.atomic_write import atomic_output
from renderer.scene.errors import SceneError
from renderer.scene.limits import MemoryBudget

ENVIRONMENT_EXTENSIONS = (".exr", ".hdr", ".pfm")
# Bytes per pixel while an environment map is read, checked against the memory budget from the
# header's size before any pixel is decoded: the decoder's channels (up to 4 of float32), the
# RGB image (float32) and its flipped or stacked copy, and the finiteness and sign masks.
_EXR_BYTES_PER_CHANNEL = 4
_READ_BYTES_PER_PIXEL = 2 * 3 * 4 + 2 * 3
_RADIANCE_HEADER_LIMIT = 1 << 16  # bytes searched for the end of a Radiance header


class NegativePixelsWarning(UserWarning):
    """An environment map had negative values (lossy-compression ringing); they were clamped to 0."""


def read_environment(path: str | os.PathLike, budget: Optional[MemoryBudget] = None) -> np.ndarray:
    """Load an .exr or .hdr environment map as float32 (H, W, 3), row 0 = top.

    Raises SceneError for a missing, unsupported, unreadable or non-finite map, and for one whose
    header declares more pixels than `budget` (default: `MemoryBudget.from_settings()`) allows,
    before anything is decoded. Negative values are clamped to 0 with a NegativePixelsWarning: a
    light source cannot emit negative radiance.
    """
    name = path  # errors show the path exactly as the caller gave it
    path = Path(path)
    if not path.is_file():
        raise SceneError(name, "environment map not found")
    budget = budget or MemoryBudget.from_settings()
    extension = path.suffix.lower()
    if extension == ".exr":
        image = _read_exr_rgb(name, budget)
    elif extension == ".hdr":
        image = _read_radiance_hdr(name, budget)
    elif extension == ".pfm":
        image = _read_pfm(name, budget)
    else:
        raise SceneError(
            name,
            f"unsupported environment map format '{path.suffix or '(none)'}' "
            f"(expected one of {', '.join(ENVIRONMENT_EXTENSIONS)})",
        )

    non_finite = int(np.count_nonzero(~np.isfinite(image).all(axis=2)))
    if non_finite:
        raise SceneError(name, f"{non_finite} pixels have non-finite values (NaN or infinity)")
    negative = image < 0
    negative_values = int(np.count_nonzero(negative))
    if negative_values:
        negative_pixels = int(np.count_nonzero(negative.any(axis=2)))
        warnings.warn(
            f"{os.fspath(name)}: clamped {negative_values} negative values "
            f"(in {negative_pixels} pixels) to 0",
            NegativePixelsWarning,
            stacklevel=2,
        )
        np.maximum(image, 0.0, out=image)
    return image


def read_exr(path: str | os.PathLike, budget: Optional[MemoryBudget] = None) -> np.ndarray:
    """Read an EXR as float32 (H, W, 3), row 0 = top, values untouched (no clamping); refused
    like `read_environment` when its header asks for more than `budget`."""
    if not Path(path).is_file():
        raise SceneError(path, "file not found")
    return _read_exr_rgb(path, budget or MemoryBudget.from_settings())


def write_exr(path: str | os.PathLike, rgb: np.ndarray, metadata: dict[str, str] | None = None,
              layers: dict[str, np.ndarray] | None = None) -> None:
    """Write linear float RGB (H, W, 3), row 0 = top, as a float32 ZIP-compressed EXR; `metadata`
    becomes string attributes of the header; `layers` are further images of the same size, each
    named layer.R/.G/.B (H, W, 3) or a single channel (H, W). Atomic: a kill leaves the previous
    file whole."""
    import OpenEXR

    pixels = np.ascontiguousarray(_check_rgb_shape(rgb), dtype=np.float32)
    channels = {"RGB": pixels}
    for name, layer in (layers or {}).items():
        layer = np.asarray(layer)
        if layer.shape[:2] != pixels.shape[:2] or layer.ndim not in (2, 3) or (layer.ndim == 3 and layer.shape[2] != 3):
            raise ValueError(f"EXR layer '{name}' has shape {layer.shape}, expected {pixels.shape[:2]} (+ 3 channels)")
        channels[name] = np.ascontiguousarray(layer, dtype=np.float32)
    header = {**_text_metadata(metadata), "compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with atomic_output(path) as temporary, OpenEXR.File(header, channels) as exr:
        exr.write(str(temporary))


def read_exr_layers(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """Every layer of an EXR as float32 arrays: "RGB" and the named ones (H, W, 3), single
    channels (H, W). For reading back what write_exr wrote (tests, tools)."""
    import OpenEXR

    with OpenEXR.File(os.fspath(path)) as exr:
        return {name: np.asarray(channel.pixels, dtype=np.float32) for name, channel in exr.channels().items()}


def write_png(path: str | os.PathLike, rgb: np.ndarray, metadata: dict[str, str] | None = None) -> None:
    """Write display-referred RGB (H, W, 3): uint8 as is, floats in [0, 1] (clipped) quantised;
    `metadata` becomes tEXt chunks. Atomic: a kill leaves the previous file whole."""
    import imageio.v3 as iio
    from PIL.PngImagePlugin import PngInfo

    rgb = _check_rgb_shape(rgb)
    if rgb.dtype != np.uint8:
        rgb = np.clip(np.nan_to_num(rgb.astype(np.float32), nan=0.0), 0.0, 1.0)
        rgb = np.floor(rgb * 255.0 + 0.5).astype(np.uint8)
    text = PngInfo()
    for key, value in _text_metadata(metadata).items():
        text.add_text(key, value)
    with atomic_output(path) as temporary:
        iio.imwrite(temporary, rgb, extension=".png", pnginfo=text)


def _text_metadata(metadata: dict[str, str] | None) -> dict[str, str]:
    return {str(key): str(value) for key, value in (metadata or {}).items()}


def _check_rgb_shape(rgb: np.ndarray) -> np.ndarray:
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.shape[0] == 0 or rgb.shape[1] == 0:
        raise ValueError(f"expected an image of shape (height, width, 3), got {rgb.shape}")
    return rgb


def _check_pixels(path, budget: MemoryBudget, width: int, height: int, what: str,
                  bytes_per_pixel: int) -> None:
    if width < 1 or height < 1:
        raise SceneError(path, f"{what} header declares an empty image ({width}x{height})")
    budget.check(path, f"reading this {width}x{height} {what}", width * height * bytes_per_pixel)


def _read_exr_rgb(path: str | os.PathLike, budget: MemoryBudget) -> np.ndarray:
    import OpenEXR

    try:
        with OpenEXR.File(os.fspath(path), header_only=True) as exr:
            header = exr.header()  # valid while the file is open
            low, high = (np.asarray(corner, dtype=np.int64) for corner in header["dataWindow"])
            channel_count = len(header["channels"])
    except Exception as error:  # the binding raises plain Exceptions/RuntimeErrors on bad files
        raise SceneError(path, f"cannot read EXR header ({_one_line(error)})") from None
    width, height = (int(v) for v in high - low + 1)
    _check_pixels(path, budget, width, height, "EXR",
                  channel_count * _EXR_BYTES_PER_CHANNEL + _READ_BYTES_PER_PIXEL)
    try:
        # Separate channels so R/G/B in mixed half/float types or with alpha all read the same way.
        with OpenEXR.File(os.fspath(path), separate_channels=True) as exr:
            channels = {name: channel.pixels for name, channel in exr.channels().items()}
    except Exception as error:  # the binding raises plain Exceptions/RuntimeErrors on bad files
        raise SceneError(path, f"cannot read EXR file ({_one_line(error)})") from None

    if all(name in channels for name in "RGB"):
        planes = [channels[name] for name in "RGB"]
    elif "Y" in channels:  # luminance-only map: grey
        planes = [channels["Y"]] * 3
    else:
        found = ", ".join(sorted(channels)) or "none"
        raise SceneError(path, f"EXR has no R, G, B (or Y) channels (found: {found})")
    image = np.stack([np.asarray(plane, dtype=np.float32) for plane in planes], axis=2)
    if image.ndim != 3 or image.shape[0] == 0 or image.shape[1] == 0:
        raise SceneError(path, "EXR image is empty")
    return image


def _radiance_size(path: str | os.PathLike) -> tuple[int, int, int]:
    """(width, height, bytes of pixel data) of a Radiance file, from its header alone."""
    with open(path, "rb") as f:
        head = f.read(_RADIANCE_HEADER_LIMIT)
        total = os.fstat(f.fileno()).st_size
    if not head.startswith((b"#?RADIANCE", b"#?RGBE")):
        raise SceneError(path, "cannot read Radiance HDR file (no '#?RADIANCE' signature)")
    end = head.find(b"\n\n")
    if end < 0:
        raise SceneError(path, "cannot read Radiance HDR file (no end of header in its first 64 KiB)")
    line_end = head.find(b"\n", end + 2)
    resolution = head[end + 2:line_end if line_end >= 0 else len(head)].decode("latin-1").strip()
    # OpenCV reads the standard orientation only: rows top to bottom, columns left to right.
    match = re.fullmatch(r"-Y (\d{1,10}) \+X (\d{1,10})", resolution)
    if match is None:
        raise SceneError(path, f"cannot read Radiance HDR file (resolution line '{resolution[:40]}'; "
                               "expected '-Y height +X width')")
    height, width = int(match.group(1)), int(match.group(2))
    return width, height, total - (line_end + 1 if line_end >= 0 else len(head))


def _radiance_min_bytes(width: int, height: int) -> int:
    """The fewest bytes of pixel data a Radiance reader accepts for this size: per scanline, flat
    RGBE (4 bytes a pixel) or, for widths 8..32767, run-length encoding (a 4-byte marker, then
    each of the 4 components in runs of at most 127 bytes, 2 bytes a run)."""
    flat = 4 * width
    if 8 <= width <= 0x7FFF:
        return height * min(flat, 4 + 4 * 2 * math.ceil(width / 127))
    return height * flat


def _read_radiance_hdr(path: str | os.PathLike, budget: MemoryBudget) -> np.ndarray:
    import cv2

    width, height, data_bytes = _radiance_size(path)
    needed = _radiance_min_bytes(width, height)
    if data_bytes < needed:
        raise SceneError(path, f"cannot read Radiance HDR file (truncated: its header declares "
                               f"{width}x{height} pixels, at least {needed} bytes of pixel data, and "
                               f"{data_bytes} follow)")
    _check_pixels(path, budget, width, height, "Radiance HDR map", _READ_BYTES_PER_PIXEL)
    # OpenCV logs its own multi-line error for corrupt files; our SceneError says it in one line.
    previous_level = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    try:
        bgr = cv2.imread(os.fspath(path), cv2.IMREAD_ANYDEPTH | cv2.IMREAD_COLOR)
    except cv2.error as error:  # e.g. more pixels than OpenCV's own limit (CV_IO_MAX_IMAGE_PIXELS)
        raise SceneError(path, f"cannot read Radiance HDR file ({_one_line(error)})") from None
    finally:
        cv2.utils.logging.setLogLevel(previous_level)
    if bgr is None or bgr.ndim != 3 or bgr.shape[2] != 3 or bgr.size == 0:
        raise SceneError(path, "cannot read Radiance HDR file (corrupt or not RGBE)")
    return np.ascontiguousarray(bgr[:, :, ::-1], dtype=np.float32)


def _read_pfm(path: str | os.PathLike, budget: MemoryBudget) -> np.ndarray:
    """A portable float map (pbrt's and Tungsten's scenes ship their maps so): its header read here
    for the budget, its pixels by OpenCV (which turns them top row first)."""
    import cv2

    with open(path, "rb") as f:
        header = f.read(256).split(maxsplit=3)
    try:
        kind, width, height = header[0], int(header[1]), int(header[2])
    except (IndexError, ValueError):
        raise SceneError(path, "cannot read PFM file (no 'PF' header with a width and height)") from None
    if kind not in (b"PF", b"Pf") or width <= 0 or height <= 0:
        raise SceneError(path, "cannot read PFM file (no 'PF' header with a width and height)")
    _check_pixels(path, budget, width, height, "PFM map", _READ_BYTES_PER_PIXEL)
    image = cv2.imread(os.fspath(path), cv2.IMREAD_UNCHANGED)
    if image is None or image.shape[:2] != (height, width):
        raise SceneError(path, "cannot read PFM file (truncated or corrupt)")
    if image.ndim == 2:  # "Pf": one grey channel
        image = np.repeat(image[:, :, None], 3, axis=2)
    return np.ascontiguousarray(image[:, :, 2::-1], dtype=np.float32)


def _one_line(error: Exception) -> str:
    text = str(error).strip().splitlines()
    return text[0] if text else type(error).__name__

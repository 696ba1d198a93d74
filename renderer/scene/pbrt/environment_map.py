"""pbrt-v4's image infinite light made into Lantern's environment map. pbrt stores the sphere in an
equal-area square (Clarberg's octahedral mapping: util/math.cpp EqualAreaSphereToSquare), Lantern
a latitude-longitude map (renderer/lights/environment.py's convention: u = atan2(x, -z) / 2pi,
v = acos(y) / pi, row 0 the zenith). The square is resampled into a map once, with the light's
rotation (and the scene's mirror, where pbrt's image needs one) baked in, and written as an EXR
to a cache folder keyed by the source's contents and that orientation."""
from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

from renderer.output.image_io import read_environment, write_exr

CACHE_FOLDER = "pbrt-environments"


def cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "lantern" / CACHE_FOLDER


def equal_area_square(w: np.ndarray) -> np.ndarray:
    """(N, 2) points of pbrt's equal-area square in [0, 1]^2 for (N, 3) unit directions."""
    x, y, z = np.abs(w[:, 0]), np.abs(w[:, 1]), np.abs(w[:, 2])
    r = np.sqrt(np.maximum(1.0 - z, 0.0))
    a, b = np.maximum(x, y), np.minimum(x, y)
    b = np.divide(b, a, out=np.zeros_like(b), where=a > 0)
    phi = np.arctan(b) * 2.0 / np.pi
    phi = np.where(x < y, 1.0 - phi, phi)
    v = phi * r
    u = r - v
    south = w[:, 2] < 0
    u, v = np.where(south, 1.0 - v, u), np.where(south, 1.0 - u, v)
    u, v = np.copysign(u, w[:, 0]), np.copysign(v, w[:, 1])
    return np.stack([0.5 * (u + 1.0), 0.5 * (v + 1.0)], axis=1)


def _bilinear(image: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """pbrt's Image::Bilerp (texel centres at half-integers), clamped at the edges."""
    h, w = image.shape[:2]
    x, y = uv[:, 0] * w - 0.5, uv[:, 1] * h - 0.5
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]

    def at(yy, xx):
        return image[np.clip(yy, 0, h - 1), np.clip(xx, 0, w - 1)]

    return ((1 - fx) * (1 - fy) * at(y0, x0) + fx * (1 - fy) * at(y0, x0 + 1)
            + (1 - fx) * fy * at(y0 + 1, x0) + fx * fy * at(y0 + 1, x0 + 1))


def latlong_from_square(square: np.ndarray, world_to_light: np.ndarray, height: int) -> np.ndarray:
    """The (height, 2 height, 3) map Lantern looks up world directions in."""
    width = 2 * height
    theta = np.pi * np.arange(height) / max(height - 1, 1)
    phi = 2.0 * np.pi * (np.arange(width) + 0.5) / width
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    d = np.stack(np.broadcast_arrays(st * np.sin(phi), ct, -st * np.cos(phi)), axis=-1).reshape(-1, 3)
    w = d @ world_to_light.T
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    return _bilinear(square.astype(np.float64), equal_area_square(w)).reshape(height, width, 3).astype(np.float32)


def converted_map(path: Path, world_to_light: np.ndarray, budget=None) -> Path:
    """The cached lat-long EXR of pbrt's equal-area map at `path` seen through `world_to_light`."""
    key = hashlib.sha256(path.read_bytes() + np.round(world_to_light, 9).tobytes()).hexdigest()[:32]
    target = cache_dir() / f"{key}.exr"
    if not target.is_file():
        square = read_environment(path, budget)
        if square.shape[0] != square.shape[1]:
            raise ValueError(f"is {square.shape[1]}x{square.shape[0]}, not a square equal-area map")
        target.parent.mkdir(parents=True, exist_ok=True)
        write_exr(target, latlong_from_square(square, world_to_light, max(square.shape[0], 16)))  # atomic
    return target

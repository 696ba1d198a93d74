"""A texture made of two (pbrt's `mix` and `scale` textures), baked into one image.

Lantern's texture slots read one image each, so a mix is computed texel by texel when the scene
is assembled: (1 - amount) * first + amount * second, or first * second. Both lookups being
linear in the texels, the baked image reads exactly as the formula wherever the operands' images
have one size and share the spec's uv mapping, wrap and filter (the pbrt reader makes the spec
so, and warns where the operands' mappings differ). Operands of other sizes are resampled to the
largest at its texel centres with the spec's filter; a colour operand is the same everywhere.
"""
from __future__ import annotations

import numpy as np

from renderer.scene.description import TextureSpec
from renderer.scene.limits import MemoryLedger
from renderer.scene.mesh_model import TextureImage


def mixed_image(spec: TextureSpec, ledger: MemoryLedger, texture_image) -> TextureImage:
    """The baked image; `texture_image(spec, ledger)` reads an operand's (texture_images.py's)."""
    if spec.kind not in ("mix", "product") or len(spec.operands) != 2:
        raise ValueError(f"a {spec.kind} texture with {len(spec.operands)} operands cannot be baked")
    textures = [texture for _, texture in spec.operands]
    if spec.kind == "mix":
        textures.append(spec.amount[1])
    images = [None if t is None else texture_image(t, ledger).linear() for t in textures]
    sizes = [im.shape[:2] for im in images if im is not None]
    if not sizes:
        raise ValueError(f"a {spec.kind} texture of colours alone is a colour, not an image")
    height, width = max(h for h, _ in sizes), max(w for _, w in sizes)
    ledger.charge("<texture>", f"{spec.kind} texture ({width}x{height})", height * width * 4 * 4 * 2)
    values = [_resampled(im, height, width, spec) for im in images]

    def operand(i: int) -> np.ndarray:
        rgb = np.asarray(spec.operands[i][0], np.float32)
        return rgb if values[i] is None else values[i][..., :3] * rgb

    first, second = operand(0), operand(1)
    if spec.kind == "product":
        rgb = first * second
    else:
        amount = np.float32(spec.amount[0]) * (np.float32(1.0) if values[2] is None else values[2][..., :1])
        rgb = (np.float32(1.0) - amount) * first + amount * second
    pixels = np.ones((height, width, 4), np.float32)
    pixels[..., :3] = np.broadcast_to(rgb, (height, width, 3))
    return TextureImage(pixels, srgb=False, label=f"{spec.kind} texture")


def _resampled(image, height: int, width: int, spec: TextureSpec):
    """The image read at the texel centres of a height x width grid over the same uv square."""
    if image is None or image.shape[:2] == (height, width):
        return image
    rows = _taps(image.shape[0], height, spec)
    cols = _taps(image.shape[1], width, spec)
    out = np.zeros((height, width, image.shape[2]), np.float32)
    for r, wr in rows:
        for c, wc in cols:
            out += (wr[:, None] * wc[None, :])[..., None] * image[r][:, c]
    return out


def _taps(source: int, target: int, spec: TextureSpec) -> list:
    """(indices, weights) pairs along one axis: where target texel centres fall in the source."""
    x = (np.arange(target, dtype=np.float64) + 0.5) * source / target - 0.5
    if spec.nearest:
        return [(_wrapped(np.floor(x + 0.5).astype(np.int64), source, spec.wrap), np.ones(target, np.float32))]
    lo = np.floor(x).astype(np.int64)
    t = (x - lo).astype(np.float32)
    return [(_wrapped(lo, source, spec.wrap), 1.0 - t), (_wrapped(lo + 1, source, spec.wrap), t)]


def _wrapped(index: np.ndarray, size: int, wrap: str) -> np.ndarray:
    if wrap == "clamp":
        return np.clip(index, 0, size - 1)
    if wrap == "mirror":
        period = np.mod(index, 2 * size)
        return np.where(period < size, period, 2 * size - 1 - period)
    return np.mod(index, size)

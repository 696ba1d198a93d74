"""All textures of a scene in ONE float32 RGBA atlas, plus a numpy reference sampler.

The renderer uploads `TextureAtlas.atlas` as a single field and a table of `rects`; every texture
lookup goes through the same code whatever the image. This module is the contract for the Taichi
sampler; `sample_bilinear` below is its numpy reference, to test a kernel against.

Layout
------
- `atlas` is float32 (H, W, 4), indexed `atlas[y, x]`: row 0 is the TOP row, as in the images.
  Images are copied unchanged (values are already linear, see `mesh_model`); grey images are
  replicated to RGB, a missing alpha is 1.
- `rects[i] = (x, y, w, h)` (int32): image i occupies `atlas[y:y+h, x:x+w]`, its texel (i, j)
  (column i, row j, row 0 at the top) is `atlas[y + j, x + i]`. The rectangle excludes padding.
- Around each rectangle there are `padding` texels on every side that REPLICATE the nearest edge
  texel (clamp-to-edge extension; corners replicate the corner texel). Padding never belongs to
  another image, so a lookup that strays up to `padding` texels outside its rectangle reads its
  own edge, never a neighbour. Unused atlas space is zero.

Sampling (what the Taichi sampler must do, in this order)
---------------------------------------------------------
1. UV transform: `uv' = (M @ (u, v, 1))[:2]` with the slot's KHR_texture_transform matrix M.
   UVs use the glTF frame: (0, 0) is the top-left corner of the image, v grows DOWN.
2. Continuous texel coordinates, texel CENTRES at half-integers: `s = u' * w - 0.5`,
   `t = v' * h - 0.5`. So u' = (i + 0.5) / w lands exactly on texel i.
3. Bilinear: `i0 = floor(s)`, `fx = s - i0`, `i1 = i0 + 1` (same for t -> j0, j1, fy).
4. Wrap EACH of the integer indices i0, i1 (with w) and j0, j1 (with h) in IMAGE texel space,
   before adding the rectangle offset:
     repeat: `i mod w`, a non-negative modulo (Python `%`; in C-like code `((i % w) + w) % w`)
     clamp:  `min(max(i, 0), w - 1)`
     mirror: `m = i mod 2w; if m >= w: m = 2w - 1 - m` (glTF MIRRORED_REPEAT)
   Every wrapped index is inside the rectangle, so filtering never reads another image and the
   seams of a repeating texture are correct; padding is only a safety margin (e.g. for a sampler
   that clamps in atlas space, or float round-off).
5. Fetch `atlas[y + j, x + i]` for the four (i, j), blend with (fx, fy).
Nearest filtering: `i = floor(u' * w)`, `j = floor(v' * h)`, wrapped as in step 4.
Non-finite UVs should be treated as (0, 0) before step 2 (the numpy reference does so).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from renderer.scene.mesh_model import WRAP_MODES

WRAP_REPEAT, WRAP_CLAMP, WRAP_MIRROR = 0, 1, 2
WRAP_CODES = {"repeat": WRAP_REPEAT, "clamp": WRAP_CLAMP, "mirror": WRAP_MIRROR}
assert tuple(WRAP_CODES) == WRAP_MODES

DEFAULT_PADDING = 2  # texels; bilinear needs 1, the second absorbs float round-off


@dataclass
class TextureAtlas:
    atlas: np.ndarray  # float32 (H, W, 4)
    rects: np.ndarray  # int32 (N, 4): x, y, w, h of each image, padding excluded
    padding: int

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in texels."""
        return int(self.atlas.shape[1]), int(self.atlas.shape[0])


def as_rgba(image: np.ndarray) -> np.ndarray:
    """float32 (H, W, 4) from (H, W), (H, W, 1|2|3|4): grey replicated to RGB, alpha 1 if missing."""
    a = np.asarray(image, dtype=np.float32)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3 or a.shape[2] not in (1, 2, 3, 4) or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(f"expected an (H, W) or (H, W, 1..4) image, got shape {np.shape(image)}")
    h, w, c = a.shape
    out = np.ones((h, w, 4), dtype=np.float32)
    if c in (1, 2):
        out[:, :, :3] = a[:, :, :1]
        if c == 2:
            out[:, :, 3] = a[:, :, 1]
    else:
        out[:, :, :c] = a
    return out


def pack_atlas(images: list[np.ndarray], padding: int = DEFAULT_PADDING,
               width: int | None = None) -> TextureAtlas:
    """Pack images into one atlas with a shelf packer (tallest first, left to right, top down).

    `width` is the atlas width in texels; by default about the square root of the total padded
    area (at least the widest padded image), so the atlas comes out roughly square. An empty list
    gives a 1x1 atlas with no rectangles.
    """
    if padding < 0:
        raise ValueError("padding must be >= 0")
    rgba = [as_rgba(im) for im in images]
    if not rgba:
        return TextureAtlas(np.zeros((1, 1, 4), dtype=np.float32), np.zeros((0, 4), dtype=np.int32),
                            padding)
    sizes = [(im.shape[1] + 2 * padding, im.shape[0] + 2 * padding) for im in rgba]  # padded w, h
    widest = max(w for w, _ in sizes)
    if width is None:
        width = max(widest, int(math.ceil(math.sqrt(sum(w * h for w, h in sizes)))))
    elif width < widest:
        raise ValueError(f"atlas width {width} is narrower than the widest padded image ({widest})")

    order = sorted(range(len(rgba)), key=lambda i: (-sizes[i][1], -sizes[i][0], i))
    origins = [(0, 0)] * len(rgba)  # padded rectangle origins
    shelf_y, shelf_h, cursor_x = 0, 0, 0
    for i in order:
        w, h = sizes[i]
        if cursor_x + w > width:  # start a new shelf below the current one
            shelf_y += shelf_h
            shelf_h, cursor_x = 0, 0
        origins[i] = (cursor_x, shelf_y)
        cursor_x += w
        shelf_h = max(shelf_h, h)
    height = shelf_y + shelf_h

    atlas = np.zeros((height, width, 4), dtype=np.float32)
    rects = np.zeros((len(rgba), 4), dtype=np.int32)
    for i, im in enumerate(rgba):
        ox, oy = origins[i]
        w, h = sizes[i]
        atlas[oy:oy + h, ox:ox + w] = np.pad(im, ((padding, padding), (padding, padding), (0, 0)),
                                             mode="edge")
        rects[i] = (ox + padding, oy + padding, im.shape[1], im.shape[0])
    return TextureAtlas(atlas, rects, padding)


def wrap_index(i: np.ndarray, n: int, mode: str | int) -> np.ndarray:
    """Wrap integer texel indices into [0, n) (step 4 of the module docs)."""
    code = WRAP_CODES[mode] if isinstance(mode, str) else int(mode)
    i = np.asarray(i, dtype=np.int64)
    if code == WRAP_REPEAT:
        return np.mod(i, n)
    if code == WRAP_CLAMP:
        return np.clip(i, 0, n - 1)
    if code == WRAP_MIRROR:
        m = np.mod(i, 2 * n)
        return np.where(m >= n, 2 * n - 1 - m, m)
    raise ValueError(f"unknown wrap mode {mode!r}")


def sample_bilinear(tex: TextureAtlas, index: int, uv: np.ndarray, wrap_s: str | int = "repeat",
                    wrap_t: str | int = "repeat", matrix: np.ndarray | None = None) -> np.ndarray:
    """Reference bilinear lookup of texture `index` at uv (..., 2); returns (..., 4) float32."""
    x, y, w, h = (int(v) for v in tex.rects[index])
    uv = np.asarray(uv, dtype=np.float64)
    if matrix is not None:
        m = np.asarray(matrix, dtype=np.float64)
        uv = uv @ m[:2, :2].T + m[:2, 2]
    uv = np.where(np.isfinite(uv), uv, 0.0)
    s = uv[..., 0] * w - 0.5
    t = uv[..., 1] * h - 0.5
    i0 = np.floor(s)
    j0 = np.floor(t)
    fx = (s - i0)[..., None]
    fy = (t - j0)[..., None]
    i0 = i0.astype(np.int64)
    j0 = j0.astype(np.int64)
    ia, ib = wrap_index(i0, w, wrap_s) + x, wrap_index(i0 + 1, w, wrap_s) + x
    ja, jb = wrap_index(j0, h, wrap_t) + y, wrap_index(j0 + 1, h, wrap_t) + y
    a = tex.atlas
    top = a[ja, ia] * (1 - fx) + a[ja, ib] * fx
    bottom = a[jb, ia] * (1 - fx) + a[jb, ib] * fx
    return (top * (1 - fy) + bottom * fy).astype(np.float32)

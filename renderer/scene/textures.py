"""All textures of a scene in one atlas per storage kind, plus a numpy reference sampler.

The renderer uploads the pages of a `TextureAtlas` and a table of `rects`; every texture lookup
goes through the same code whatever the image. This module is the contract for the Taichi
sampler (`renderer.materials.texture_sampler`); `sample_bilinear` below is its numpy reference.

Layout
------
- Images keep their precision (see `renderer.scene.mesh_model.TextureImage`). Each storage kind
  has its own page, indexed `page[y, x]`, row 0 the TOP row as in the images:
    "rgba8": uint8 (H, W, 4), i.e. one 32-bit word per texel, R in the lowest byte;
    "half":  float16 (H, W, 4), two 32-bit words per texel (R | G << 16, B | A << 16);
    "float": float32 (H, W, 4).
  A page that holds no image is a single zero texel. Texels are stored as the file encodes them:
  colour decoding happens in the lookup (step 5), so one copy serves colour and data slots.
- `rects[i] = (x, y, w, h, storage, srgb)` (int32) for image entry i: its texels are
  `pages[storage][y:y+h, x:x+w]`, texel (i, j) (column i, row j from the top) at
  `[y + j, x + i]`; `storage` is the index of its kind in STORAGES, `srgb` is 1 when RGB is
  sRGB-encoded. Entries sharing one pixel array share one rectangle.
- Around each rectangle there are `padding` texels on every side that REPLICATE the nearest edge
  texel (clamp-to-edge extension; corners replicate the corner texel). Padding never belongs to
  another image, so a lookup that strays up to `padding` texels outside its rectangle reads its
  own edge, never a neighbour. Unused page space is zero.

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
5. Fetch the four texels and DECODE EACH before blending: rgba8 bytes k -> k / 255, except RGB
   of an sRGB entry -> `SRGB8_TO_LINEAR[k]` (exact table); half / float values as stored, RGB of
   an sRGB entry through the sRGB curve. Alpha is never colour-decoded. Then blend with (fx, fy).
   (Decoding after blending would mix encoded values: wrong at every edge of a colour texture.)
Nearest filtering: `i = floor(u' * w)`, `j = floor(v' * h)`, wrapped as in step 4.
Non-finite UVs should be treated as (0, 0) before step 2 (the numpy reference does so).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from renderer.scene.mesh_model import STORAGES, WRAP_MODES, TextureImage
from renderer.scene.srgb import SRGB8_TO_LINEAR, srgb_to_linear
from renderer.scene.texture_mips import mip_chain

WRAP_REPEAT, WRAP_CLAMP, WRAP_MIRROR = 0, 1, 2
WRAP_CODES = {"repeat": WRAP_REPEAT, "clamp": WRAP_CLAMP, "mirror": WRAP_MIRROR}
assert tuple(WRAP_CODES) == WRAP_MODES

STORE_RGBA8, STORE_HALF, STORE_FLOAT = (STORAGES.index(s) for s in ("rgba8", "half", "float"))
_PAGE_DTYPES = {STORE_RGBA8: np.uint8, STORE_HALF: np.float16, STORE_FLOAT: np.float32}

# How lookups read textures over a pixel's footprint (RenderSettings.texture_filter).
TEXTURE_FILTERS = ("anisotropic", "trilinear", "none")

DEFAULT_PADDING = 2  # texels; bilinear needs 1, the second absorbs float round-off


@dataclass
class TextureAtlas:
    pages: dict[int, np.ndarray]  # storage code -> (H, W, 4) page (module docs); all three present
    rects: np.ndarray  # int32 (N, 6): x, y, w, h, storage, srgb of each image entry
    padding: int
    # Mip-map levels (renderer/scene/texture_mips.py), when packed with them: rows as `rects` for
    # every level below 0, and for entry i the first of its rows and their count (levels 1..count).
    level_rects: np.ndarray = field(default_factory=lambda: np.zeros((0, 6), np.int32))
    level_span: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int32))

    def page_size(self, storage: int) -> tuple[int, int]:
        """(width, height) in texels of one storage kind's page."""
        page = self.pages[storage]
        return int(page.shape[1]), int(page.shape[0])

    def texels(self, index: int) -> np.ndarray:
        """The stored texels of entry `index` (padding excluded), as in its page."""
        x, y, w, h, storage, _ = (int(v) for v in self.rects[index])
        return self.pages[storage][y:y + h, x:x + w]

    @property
    def storages(self) -> frozenset[int]:
        """The storage kinds that hold at least one image."""
        return frozenset(int(s) for s in self.rects[:, 4])

    @property
    def nbytes(self) -> int:
        """Bytes of the pages that hold images (what the device allocates for them)."""
        return sum(self.pages[s].nbytes for s in self.storages)


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


def as_texture_image(image) -> TextureImage:
    """A `TextureImage` as is, or a linear one from an array: uint8 stays 8-bit, float16 half,
    anything else float32 (grey replicated, alpha 1 if missing, as `as_rgba`)."""
    if isinstance(image, TextureImage):
        return image
    a = np.asarray(image)
    if a.dtype == np.uint8:
        rgba = as_rgba(a)  # exact for bytes; back to uint8 below
        alpha = a.ndim == 3 and a.shape[2] in (2, 4)
        out = np.rint(rgba).astype(np.uint8)
        if not alpha:
            out[..., 3] = 255
        return TextureImage(out)
    if a.dtype == np.float16:
        return TextureImage(as_rgba(a).astype(np.float16))
    return TextureImage(as_rgba(a))


def _shelf_pack(sizes: list[tuple[int, int]], width: int | None) -> tuple[list, int, int]:
    """Origins of padded (w, h) boxes packed tallest first, left to right, top down, and the
    page (width, height). Default width: about the square root of the total area."""
    widest = max(w for w, _ in sizes)
    if width is None:
        width = max(widest, int(math.ceil(math.sqrt(sum(w * h for w, h in sizes)))))
    elif width < widest:
        raise ValueError(f"atlas width {width} is narrower than the widest padded image ({widest})")
    order = sorted(range(len(sizes)), key=lambda i: (-sizes[i][1], -sizes[i][0], i))
    origins = [(0, 0)] * len(sizes)
    shelf_y, shelf_h, cursor_x = 0, 0, 0
    for i in order:
        w, h = sizes[i]
        if cursor_x + w > width:  # start a new shelf below the current one
            shelf_y += shelf_h
            shelf_h, cursor_x = 0, 0
        origins[i] = (cursor_x, shelf_y)
        cursor_x += w
        shelf_h = max(shelf_h, h)
    return origins, width, shelf_y + shelf_h


def pack_atlas(images: list, padding: int = DEFAULT_PADDING, width: int | None = None,
               mipmaps: bool = False) -> TextureAtlas:
    """Pack images (`TextureImage`s or arrays, see `as_texture_image`) into one page per storage.

    Entries that share a pixel array are stored once. `width` forces every page's width in
    texels (it must fit the widest padded image); by default each page is roughly square.
    `mipmaps`: each image's mip-map levels are packed too (`level_rects`, `level_span`), once per
    pixel array and colour decoding (a colour and a data reading of one file average differently).
    """
    if padding < 0:
        raise ValueError("padding must be >= 0")
    entries = [as_texture_image(im) for im in images]
    count = len(entries)
    level_span = np.zeros((count if mipmaps else 0, 2), np.int32)
    if mipmaps:
        chains: dict[tuple, tuple[int, int]] = {}  # (id(pixels), srgb) -> (first row, count)
        levels: list = []
        for i, entry in enumerate(entries[:count]):
            key = (id(entry.pixels), entry.srgb)
            if key not in chains:
                chain = mip_chain(entry)
                chains[key] = (len(levels), len(chain))
                levels += chain
            level_span[i] = chains[key]
        entries += levels
    unique: dict[int, int] = {}  # id(pixels) -> index of its first entry
    by_storage: dict[int, list[int]] = {s: [] for s in _PAGE_DTYPES}
    for i, entry in enumerate(entries):
        if id(entry.pixels) not in unique:
            unique[id(entry.pixels)] = i
            by_storage[STORAGES.index(entry.storage)].append(i)

    rects = np.zeros((len(entries), 6), dtype=np.int32)
    pages = {}
    for storage, members in by_storage.items():
        dtype = _PAGE_DTYPES[storage]
        if not members:
            pages[storage] = np.zeros((1, 1, 4), dtype=dtype)
            continue
        sizes = [(entries[i].shape[1] + 2 * padding, entries[i].shape[0] + 2 * padding)
                 for i in members]
        origins, page_w, page_h = _shelf_pack(sizes, width)
        page = np.zeros((page_h, page_w, 4), dtype=dtype)
        for i, (ox, oy), (w, h) in zip(members, origins, sizes):
            page[oy:oy + h, ox:ox + w] = np.pad(entries[i].pixels,
                                                ((padding, padding), (padding, padding), (0, 0)),
                                                mode="edge")
            rects[i, :5] = (ox + padding, oy + padding, w - 2 * padding, h - 2 * padding, storage)
        pages[storage] = page
    for i, entry in enumerate(entries):
        rects[i, :5] = rects[unique[id(entry.pixels)], :5]
        rects[i, 5] = int(entry.srgb)
    if mipmaps:
        return TextureAtlas(pages, rects[:count], padding, rects[count:], level_span)
    return TextureAtlas(pages, rects, padding)


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


def decode_texels(raw: np.ndarray, storage: int, srgb: bool) -> np.ndarray:
    """Stored texels (..., 4) of one storage kind as linear float32 values (step 5)."""
    if storage == STORE_RGBA8:
        out = raw.astype(np.float32) / np.float32(255.0)
        if srgb:
            out[..., :3] = SRGB8_TO_LINEAR[raw[..., :3]]
        return out
    out = raw.astype(np.float32)
    if srgb:
        out[..., :3] = srgb_to_linear(out[..., :3])
    return out


def level_rect(tex: TextureAtlas, index: int, level: int) -> np.ndarray:
    """The rect row of entry `index`'s mip level `level` (0: the image itself)."""
    if level == 0:
        return tex.rects[index]
    first, count = (int(v) for v in tex.level_span[index])
    if not 1 <= level <= count:
        raise ValueError(f"entry {index} has mip levels 0..{count}, not {level}")
    return tex.level_rects[first + level - 1]


def sample_trilinear(tex: TextureAtlas, index: int, uv: np.ndarray, lod: float, wrap_s: str | int = "repeat",
                     wrap_t: str | int = "repeat", matrix: np.ndarray | None = None) -> np.ndarray:
    """Reference trilinear lookup: bilinear in the two levels around `lod` (clamped to the entry's
    levels), blended by its fraction; a lod of 0 or less is the bilinear lookup of the image."""
    count = int(tex.level_span[index, 1]) if len(tex.level_span) else 0
    lod = min(max(float(lod), 0.0), float(count))
    below = min(int(np.floor(lod)), count)
    frac = lod - below
    out = sample_bilinear(tex, index, uv, wrap_s, wrap_t, matrix, level=below)
    if frac > 0.0:
        above = sample_bilinear(tex, index, uv, wrap_s, wrap_t, matrix, level=below + 1)
        out = ((1.0 - frac) * out.astype(np.float64) + frac * above).astype(np.float32)
    return out


def sample_bilinear(tex: TextureAtlas, index: int, uv: np.ndarray, wrap_s: str | int = "repeat",
                    wrap_t: str | int = "repeat", matrix: np.ndarray | None = None, level: int = 0) -> np.ndarray:
    """Reference bilinear lookup of image entry `index` (its mip level `level`) at uv (..., 2);
    returns (..., 4) float32."""
    x, y, w, h, storage, srgb = (int(v) for v in level_rect(tex, index, level))
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
    page = tex.pages[storage]

    def tap(j, i):
        return decode_texels(page[j, i], storage, bool(srgb)).astype(np.float64)

    top = tap(ja, ia) * (1 - fx) + tap(ja, ib) * fx
    bottom = tap(jb, ia) * (1 - fx) + tap(jb, ib) * fx
    return (top * (1 - fy) + bottom * fy).astype(np.float32)

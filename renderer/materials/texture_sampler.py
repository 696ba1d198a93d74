"""Texture lookups on the device: every texture of a scene lives in one page per storage kind.

Follows the layout and sampling rules of `renderer.scene.textures` (its `sample_bilinear` is the
numpy reference this sampler is tested against): UV transform, texel centres at half-integers,
bilinear filtering with each tap wrapped (repeat / clamp / mirror) inside its own image, and each
tap decoded (8-bit bytes through the exact sRGB table for colour slots) BEFORE blending.

Filtering (`lookup`, what materials call): "none" reads the image itself as above; "trilinear"
and "anisotropic" read its mip-map levels (renderer/scene/texture_mips.py) at the level of the
surface's pixel footprint in texels (Surface.uv_footprint, renderer/geometry/texture_footprint.py):
trilinear at the footprint's longer axis, blending the two levels around it; anisotropic at its
shorter axis (at least the longer one / MAX_ANISOTROPY) with up to MAX_ANISOTROPY trilinear probes
spread along the longer axis. A slot's nearest flag is its magnification filter: it applies
where level 0 is read. Only what a BSDF is linear in is filtered (colours, emission, lobe and mix
weights): a footprint's mean of those gives the mean appearance. Roughness, metallic-roughness
maps, normal and bump maps, indices of refraction and Disney's scalars read level 0
(`unfiltered`): averaged, a checker of mirror and rough squares would shade as one half-rough
surface, an appearance no point of it has. Slots of texture coordinate set 1, and points without a footprint, read
level 0. Coverage (alpha) tests in traversal and bump-map gradients read level 0 (`sample`).

Pages are 32-bit integer fields (RGBA8 packed in one word per texel, half floats two to a word)
and one float32 RGBA field: no 8- or 16-bit types, so the same code runs on CUDA and Vulkan.
Only the storage kinds a scene's textures use are compiled into its kernels.
"""
import numpy as np
import taichi as ti

from renderer.scene.srgb import SRGB8_TO_LINEAR
from renderer.scene.textures import (STORE_FLOAT, STORE_HALF, STORE_RGBA8, TEXTURE_FILTERS, WRAP_CLAMP, WRAP_MIRROR,
                                     pack_atlas)
from renderer.runtime.upload import upload_fields

MAX_ANISOTROPY = 8  # probes along a footprint's longer axis, and the most it may outrun the shorter

# Texture table row: rect x, y, w, h in its page | wrap s, wrap t, uv set, nearest | storage, sRGB |
# uv matrix rows 0 and 1 | first row of its mip levels in the level table, their count.
TextureSlot = ti.types.struct(rect=ti.math.ivec4, modes=ti.math.ivec4, format=ti.math.ivec2,
                              m0=ti.math.vec3, m1=ti.math.vec3, lod=ti.math.ivec2)


def slot_arrays(slots) -> dict:
    """slots: list of (atlas rect row (x, y, w, h, storage, srgb[, first level, level count]),
    wrap_s, wrap_t, uv_set, matrix (3, 3)[, nearest]): `nearest` (default False) reads the nearest
    texel instead of filtering bilinearly; the level pair points into the atlas's `level_rects`."""
    n = len(slots)
    rows = np.zeros((n, 8), np.int32)
    for i, s in enumerate(slots):
        row = np.asarray(s[0], np.int32).ravel()
        rows[i, :len(row)] = row
    return {
        "rect": rows[:, :4].copy(),
        "modes": np.array([[s[1], s[2], s[3], int(len(s) > 5 and bool(s[5]))] for s in slots],
                          np.int32).reshape(n, 4),
        "format": rows[:, 4:6].copy(),
        "lod": rows[:, 6:8].copy(),
        "m0": np.array([np.asarray(s[4], np.float32)[0] for s in slots], np.float32).reshape(n, 3),
        "m1": np.array([np.asarray(s[4], np.float32)[1] for s in slots], np.float32).reshape(n, 3),
    }


def page_words(atlas) -> dict:
    """The pages as the device stores them: int32 words (rgba8, half) and float32 (float)."""
    return {
        STORE_RGBA8: np.ascontiguousarray(atlas.pages[STORE_RGBA8]).view(np.int32)[..., 0],
        STORE_HALF: np.ascontiguousarray(atlas.pages[STORE_HALF]).view(np.int32),
        STORE_FLOAT: np.ascontiguousarray(atlas.pages[STORE_FLOAT], dtype=np.float32),
    }


@ti.func
def _wrap(i, n, mode):
    r = i % n
    r = r + n if r < 0 else r  # non-negative modulo (repeat)
    if mode == WRAP_CLAMP:
        r = ti.min(ti.max(i, 0), n - 1)
    elif mode == WRAP_MIRROR:
        m = i % (2 * n)
        m = m + 2 * n if m < 0 else m
        r = 2 * n - 1 - m if m >= n else m
    return r


@ti.func
def _half_to_float(h):
    """IEEE half (the low 16 bits of an i32) to f32, exactly, subnormals and infinities included."""
    e = (h >> 10) & 0x1F
    m = h & 0x3FF
    bits = ((e + 112) << 23) | (m << 13)  # rebias the exponent 15 -> 127
    if e == 31:
        bits = 0x7F800000 | (m << 13)
    v = ti.bit_cast(bits, ti.f32)
    if e == 0:
        v = ti.cast(m, ti.f32) * 5.960464477539063e-08  # m * 2^-24
    return -v if (h & 0x8000) != 0 else v


@ti.func
def _srgb_to_linear(c):
    return c / 12.92 if c <= 0.04045 else ti.pow((ti.max(c, 0.04045) + 0.055) / 1.055, 2.4)


@ti.data_oriented
class TextureTable:
    def __init__(self, atlas, slots, filtering: str = "none"):
        """atlas: a `renderer.scene.textures.TextureAtlas` (None: no textures); slots as `slot_arrays`;
        filtering: one of TEXTURE_FILTERS (mip-mapped ones need the atlas packed with its levels)."""
        if filtering not in TEXTURE_FILTERS:
            raise ValueError(f"unknown texture filter '{filtering}' (choose from {', '.join(TEXTURE_FILTERS)})")
        if atlas is None or len(slots) == 0:
            atlas, slots = pack_atlas([]), []
        arrays = slot_arrays(slots) if slots else None
        # Filtering is compiled in only where some slot has levels to read.
        self.filtering = filtering if arrays is not None and np.any(arrays["lod"][:, 1] > 0) else "none"
        words = page_words(atlas)
        self.storages = frozenset(int(np.asarray(s[0])[4]) for s in slots)  # compiled in
        self.nearest = any(len(s) > 5 and bool(s[5]) for s in slots)  # nearest filtering compiled in
        self.rgba8 = ti.field(ti.i32, shape=words[STORE_RGBA8].shape[:2])
        self.half = ti.Vector.field(2, ti.i32, shape=words[STORE_HALF].shape[:2])
        self.full = ti.Vector.field(4, ti.f32, shape=words[STORE_FLOAT].shape[:2])
        self.srgb8 = ti.field(ti.f32, shape=256)
        fields = {STORE_RGBA8: self.rgba8, STORE_HALF: self.half, STORE_FLOAT: self.full}
        uploads = [(fields[s], words[s]) for s in sorted(self.storages)]
        if STORE_RGBA8 in self.storages:
            uploads.append((self.srgb8, SRGB8_TO_LINEAR))
        if uploads:
            upload_fields(uploads)
        self.count = len(slots)
        self.slots = TextureSlot.field(shape=max(1, self.count))
        if self.count:
            self.slots.from_numpy(arrays)
        self.levels = ti.Vector.field(4, ti.i32, shape=max(1, len(atlas.level_rects)))  # x, y, w, h
        if self.filtering != "none":
            self.levels.from_numpy(np.ascontiguousarray(atlas.level_rects[:, :4], np.int32))

    @property
    def filters(self) -> bool:
        """Whether lookups read mip levels, so hits must carry their footprints."""
        return self.filtering != "none"

    @ti.func
    def _texel(self, storage, srgb, j, i):
        """One texel, decoded to linear RGBA (step 5 of the atlas docs)."""
        out = ti.math.vec4(0.0)
        if ti.static(STORE_RGBA8 in self.storages):
            if storage == STORE_RGBA8:
                word = self.rgba8[j, i]
                for c in ti.static(range(4)):
                    k = (word >> (8 * c)) & 0xFF
                    out[c] = ti.cast(k, ti.f32) * (1.0 / 255.0)
                    if ti.static(c < 3):
                        if srgb != 0:
                            out[c] = self.srgb8[k]
        if ti.static(STORE_HALF in self.storages):
            if storage == STORE_HALF:
                pair = self.half[j, i]
                for c in ti.static(range(4)):
                    out[c] = _half_to_float((pair[c // 2] >> (16 * (c % 2))) & 0xFFFF)
        if ti.static(STORE_FLOAT in self.storages):
            if storage == STORE_FLOAT:
                out = self.full[j, i]
        if ti.static(STORE_HALF in self.storages or STORE_FLOAT in self.storages):
            if storage != STORE_RGBA8 and srgb != 0:
                for c in ti.static(range(3)):
                    out[c] = _srgb_to_linear(out[c])
        return out

    @ti.func
    def _footprint(self, slot_id, uv0, uv1):
        """Where a lookup of the image itself falls: the slot, its wrapped tap columns ia, ib and
        rows ja, jb (page coordinates) and the bilinear fractions fx, fy."""
        slot = self.slots[slot_id]
        uv = uv0 if slot.modes.z == 0 else uv1
        taps, fx, fy = self._taps(slot, uv, slot.rect, slot.modes.w != 0)
        return slot, taps, fx, fy

    @ti.func
    def _taps(self, slot, uv, rect, nearest):
        """The wrapped taps and bilinear fractions of texture coordinates uv in the image (or mip
        level) at `rect` of the page; `nearest`: the texel under uv at full weight."""
        h3 = ti.math.vec3(uv.x, uv.y, 1.0)
        u = slot.m0.dot(h3)
        v = slot.m1.dot(h3)
        # Non-finite UVs read texel (0, 0)'s neighbourhood instead of indexing out of bounds.
        u = u if ti.abs(u) < 1e30 else 0.0
        v = v if ti.abs(v) < 1e30 else 0.0
        w = rect.z
        h = rect.w
        s = u * w - 0.5
        t = v * h - 0.5
        if ti.static(self.nearest):
            if nearest:  # nearest: the texel under (u, v), at full weight (fx = fy = 0 below)
                s = ti.floor(u * w)
                t = ti.floor(v * h)
        s0 = ti.floor(s)
        t0 = ti.floor(t)
        i0 = ti.cast(s0, ti.i32)
        j0 = ti.cast(t0, ti.i32)
        ia = _wrap(i0, w, slot.modes.x) + rect.x
        ib = _wrap(i0 + 1, w, slot.modes.x) + rect.x
        ja = _wrap(j0, h, slot.modes.y) + rect.y
        jb = _wrap(j0 + 1, h, slot.modes.y) + rect.y
        return ti.math.ivec4(ia, ib, ja, jb), s - s0, t - t0

    @ti.func
    def _bilinear(self, slot, taps, fx, fy):
        # The four taps in one runtime loop: the texel decoder is compiled once, not four times.
        result = ti.math.vec4(0.0)
        for k in range(4):
            right = k & 1
            below = k >> 1
            weight = (fx if right != 0 else 1.0 - fx) * (fy if below != 0 else 1.0 - fy)
            texel = self._texel(slot.format.x, slot.format.y, taps[3] if below != 0 else taps[2],
                                taps[1] if right != 0 else taps[0])
            result += weight * texel
        return result

    @ti.func
    def sample(self, slot_id, uv0, uv1):
        """The image itself at the slot's texture coordinates (no mip levels)."""
        slot, taps, fx, fy = self._footprint(slot_id, uv0, uv1)
        return self._bilinear(slot, taps, fx, fy)

    @ti.func
    def unfiltered(self, slot_id, surface):
        """The slot's texture at `surface`, the image itself: for the parameters the BSDF is not
        linear in (module docs)."""
        return self.sample(slot_id, surface.uv, surface.uv1)

    @ti.func
    def lookup(self, slot_id, surface):
        """What materials read: the slot's texture at `surface`, filtered over its footprint as
        the table's filtering says (module docs)."""
        result = ti.math.vec4(0.0)
        if ti.static(not self.filters):
            result = self.sample(slot_id, surface.uv, surface.uv1)
        else:
            slot = self.slots[slot_id]
            uv = surface.uv
            fp = surface.uv_footprint
            if slot.modes.z != 0:  # texture coordinates set 1: no footprint
                uv, fp = surface.uv1, ti.math.vec4(0.0)
            result = self.filtered(slot_id, uv, fp)
        return result

    @ti.func
    def filtered(self, slot_id, uv, fp):
        """The slot's texture at uv, filtered over the footprint fp = (du, dv) of one axis of the
        pixel's footprint, then of the other (texture coordinates before the slot's transform)."""
        slot = self.slots[slot_id]
        # The footprint's axes in level-0 texels (through the slot's uv transform).
        w = ti.cast(slot.rect.z, ti.f32)
        h = ti.cast(slot.rect.w, ti.f32)
        a = ti.math.vec2(w * (slot.m0.x * fp.x + slot.m0.y * fp.y), h * (slot.m1.x * fp.x + slot.m1.y * fp.y))
        b = ti.math.vec2(w * (slot.m0.x * fp.z + slot.m0.y * fp.w), h * (slot.m1.x * fp.z + slot.m1.y * fp.w))
        la, lb = a.norm(), b.norm()
        major = ti.max(la, lb)
        width = major  # the footprint the level is chosen for, in texels
        probes = 1
        step = ti.math.vec2(0.0)  # between probes, in texture coordinates
        if ti.static(self.filtering == "anisotropic"):
            minor = ti.max(ti.min(la, lb), major / MAX_ANISOTROPY)
            # Probes where the footprint spans more than a texel, or a nearest-filtered texel's
            # edges: within one texel a bilinear lookup is already smooth (one lookup, not eight).
            if minor > 0.0 and (major > 1.0 or slot.modes.w != 0):
                probes = ti.min(ti.cast(ti.ceil(major / minor - 1e-3), ti.i32), MAX_ANISOTROPY)
                width = minor
                along = fp.xy if la >= lb else fp.zw
                step = along / ti.cast(probes, ti.f32)
        levels = slot.lod.y
        lod = 0.0
        if width > 1.0:
            lod = ti.min(ti.log(width) * 1.4426950408889634, ti.cast(levels, ti.f32))  # log2
        below = ti.min(ti.cast(ti.floor(lod), ti.i32), levels)
        frac = lod - ti.cast(below, ti.f32)
        # Probes and the two levels in runtime loops: one inlined copy of the bilinear lookup. Each
        # blend is a first value plus weighted differences, so equal values blend to themselves
        # exactly (a uniform patch reads as what the unfiltered lookup reads, to the bit).
        first = ti.math.vec4(0.0)
        spread = ti.math.vec4(0.0)
        for p in range(probes):
            at = uv + step * (ti.cast(p, ti.f32) - 0.5 * ti.cast(probes - 1, ti.f32))
            lower = ti.math.vec4(0.0)
            value = ti.math.vec4(0.0)
            for k in range(2):
                if k == 0 or frac > 0.0:
                    level = below + k
                    rect = slot.rect
                    if level > 0:
                        rect = self.levels[slot.lod.x + level - 1]
                    taps, fx, fy = self._taps(slot, at, rect, level == 0 and slot.modes.w != 0)
                    texel = self._bilinear(slot, taps, fx, fy)
                    if k == 0:
                        lower = texel
                        value = texel
                    else:
                        value = lower + frac * (texel - lower)
            if p == 0:
                first = value
            else:
                spread += value - first
        return first + spread / ti.cast(probes, ti.f32)

    @ti.func
    def gradient(self, slot_id, uv0, uv1):
        """(d/du, d/dv) of `sample` (texture coordinates before the slot's uv transform): the
        derivative of the bilinear interpolation inside the texel cell (Mitsuba's eval_1_grad),
        zero for nearest filtering. Compiled only into kernels that call it (bump maps)."""
        slot, taps, fx, fy = self._footprint(slot_id, uv0, uv1)
        d_ds = ti.math.vec4(0.0)  # along the page's texel columns and rows
        d_dt = ti.math.vec4(0.0)
        for k in range(4):
            right = k & 1
            below = k >> 1
            texel = self._texel(slot.format.x, slot.format.y, taps[3] if below != 0 else taps[2],
                                taps[1] if right != 0 else taps[0])
            d_ds += ((1.0 if right != 0 else -1.0) * (fy if below != 0 else 1.0 - fy)) * texel
            d_dt += ((1.0 if below != 0 else -1.0) * (fx if right != 0 else 1.0 - fx)) * texel
        if ti.static(self.nearest):
            if slot.modes.w != 0:
                d_ds, d_dt = ti.math.vec4(0.0), ti.math.vec4(0.0)
        # s = w (m0 . (u, v, 1)) - 1/2 and t = h (m1 . (u, v, 1)) - 1/2: the chain rule.
        w = ti.cast(slot.rect.z, ti.f32)
        h = ti.cast(slot.rect.w, ti.f32)
        d_du = d_ds * (w * slot.m0.x) + d_dt * (h * slot.m1.x)
        d_dv = d_ds * (w * slot.m0.y) + d_dt * (h * slot.m1.y)
        return d_du, d_dv

"""Texture lookups on the device: every texture of a scene lives in one RGBA atlas field.

Follows the layout and sampling rules of `renderer.scene.textures` (its `sample_bilinear` is the
numpy reference this sampler is tested against): UV transform, texel centres at half-integers,
bilinear filtering with each tap wrapped (repeat / clamp / mirror) inside its own image.
"""
import numpy as np
import taichi as ti

from renderer.scene.textures import WRAP_CLAMP, WRAP_MIRROR
from renderer.upload import upload_fields

# Texture table row: atlas rect x, y, w, h | wrap s, wrap t, uv set | uv matrix rows 0 and 1.
TextureSlot = ti.types.struct(rect=ti.math.ivec4, modes=ti.math.ivec3, m0=ti.math.vec3, m1=ti.math.vec3)


def slot_arrays(slots) -> dict:
    """slots: list of (rect (4,), wrap_s code, wrap_t code, uv_set, matrix (3, 3))."""
    n = len(slots)
    return {
        "rect": np.array([s[0] for s in slots], np.int32).reshape(n, 4),
        "modes": np.array([[s[1], s[2], s[3]] for s in slots], np.int32).reshape(n, 3),
        "m0": np.array([np.asarray(s[4], np.float32)[0] for s in slots], np.float32).reshape(n, 3),
        "m1": np.array([np.asarray(s[4], np.float32)[1] for s in slots], np.float32).reshape(n, 3),
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


@ti.data_oriented
class TextureTable:
    def __init__(self, atlas: np.ndarray | None, slots):
        if atlas is None or len(slots) == 0:
            atlas = np.zeros((1, 1, 4), np.float32)
        self.atlas = ti.Vector.field(4, ti.f32, shape=atlas.shape[:2])
        upload_fields([(self.atlas, atlas)])
        self.count = len(slots)
        self.slots = TextureSlot.field(shape=max(1, self.count))
        if self.count:
            self.slots.from_numpy(slot_arrays(slots))

    @ti.func
    def sample(self, slot_id, uv0, uv1):
        slot = self.slots[slot_id]
        uv = uv0 if slot.modes.z == 0 else uv1
        h3 = ti.math.vec3(uv.x, uv.y, 1.0)
        u = slot.m0.dot(h3)
        v = slot.m1.dot(h3)
        # Non-finite UVs read texel (0, 0)'s neighbourhood instead of indexing out of bounds.
        u = u if ti.abs(u) < 1e30 else 0.0
        v = v if ti.abs(v) < 1e30 else 0.0
        w = slot.rect.z
        h = slot.rect.w
        s = u * w - 0.5
        t = v * h - 0.5
        s0 = ti.floor(s)
        t0 = ti.floor(t)
        fx = s - s0
        fy = t - t0
        i0 = ti.cast(s0, ti.i32)
        j0 = ti.cast(t0, ti.i32)
        ia = _wrap(i0, w, slot.modes.x) + slot.rect.x
        ib = _wrap(i0 + 1, w, slot.modes.x) + slot.rect.x
        ja = _wrap(j0, h, slot.modes.y) + slot.rect.y
        jb = _wrap(j0 + 1, h, slot.modes.y) + slot.rect.y
        top = self.atlas[ja, ia] * (1.0 - fx) + self.atlas[ja, ib] * fx
        bottom = self.atlas[jb, ia] * (1.0 - fx) + self.atlas[jb, ib] * fx
        return top * (1.0 - fy) + bottom * fy

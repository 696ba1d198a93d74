"""Counter-based random numbers: every value is a pure hash of (pixel, sample, dimension, seed).

No generator state lives on the device, so an image depends only on its seed, never on thread
scheduling, and any sample of any pixel can be recomputed in isolation (the tests do that).
"""
import taichi as ti

# Where one camera sample's numbers come from: every sampler starts from these (its `start`) and
# draws each dimension from them (`key` is `sample_key` of the other three, for hashed samplers).
SampleState = ti.types.struct(pixel=ti.u32, index=ti.u32, seed=ti.u32, key=ti.u32)

# 1 / 2^24: the top 24 bits of a hash give a float in [0, 1) whose every value is exactly
# representable in f32, so the result can never round up to 1.0.
_INV_2_24 = 1.0 / 16777216.0


@ti.func
def pcg_hash(v):
    """PCG-RXS-M-XS 32-bit hash (Jarzynski and Olano 2020): good avalanche at low cost."""
    state = ti.cast(v, ti.u32) * ti.u32(747796405) + ti.u32(2891336453)
    word = ((state >> ((state >> ti.u32(28)) + ti.u32(4))) ^ state) * ti.u32(277803737)
    return (word >> ti.u32(22)) ^ word


@ti.func
def sample_key(pixel_index, sample_index, seed):
    """The key of one sample of one pixel; dimensions are drawn from it with `uniform`."""
    k = pcg_hash(ti.cast(seed, ti.u32) ^ ti.u32(0x9E3779B9))
    k = pcg_hash(k ^ ti.cast(pixel_index, ti.u32))
    return pcg_hash(k ^ ti.cast(sample_index, ti.u32))


@ti.func
def uniform(key, dim):
    """The dim-th uniform number in [0, 1) of the sample identified by key."""
    h = pcg_hash(key ^ pcg_hash(ti.cast(dim, ti.u32) + ti.u32(0x68E31DA4)))
    return ti.cast(h >> ti.u32(8), ti.f32) * _INV_2_24


@ti.func
def uniform2(key, dim):
    return ti.math.vec2(uniform(key, dim), uniform(key, dim + 1))

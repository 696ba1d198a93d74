"""Owen-scrambled, shuffled Sobol points (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)).

Every number is a pure function of (pixel, sample index, dimension id, seed), like the independent
sampler's, so images stay reproducible and any sample can be recomputed alone.

How one decision (dimension id `dim`) of camera sample `i` of a pixel is drawn:

  seed_d   = hash(pixel key + dim * odd constant)    pixel key = hash(pixel, render seed)
  j        = owen(i, seed_d)                          shuffle the sample index ("padding")
  get1d    = owen(sobol_0(j), hash_x(seed_d))
  get2d    = (owen(sobol_0(j), hash_x(seed_d)),  owen(sobol_1(j), hash_y(seed_d)))

* `owen(v, s)` is a nested uniform (Owen) scramble of the 32 bits of v, most significant first,
  done with a hash: reverse the bits, apply a Laine-Karras style permutation (each output bit k is
  input bit k XOR a function of the bits below it only, so it permutes every subtree of the bit
  trie), reverse back.
* Sobol dimensions 0 and 1 form a (0,2)-sequence: every aligned block of 2^m consecutive indices is
  a (0,m,2)-net (one point in every elementary interval of area 2^-m). Owen scrambling keeps that.
* The index shuffle `owen(i, seed_d)` maps every aligned block of 2^m indices onto another aligned
  block of 2^m indices (the bits >= m of the result depend only on the bits >= m of i), so the
  first 2^m samples of a pixel, and every later aligned block, are still a (0,m,2)-net in every 2D
  decision, while different dimension ids (and different pixels) see their points in unrelated
  orders: that decorrelates the decisions of a path without needing high Sobol dimensions.

All kernel arithmetic is 32-bit unsigned; results are the top 24 bits times 2^-24, in [0, 1) and
never rounded up to 1.0. The generator matrices of Sobol dimensions 0..3 (Joe and Kuo's direction
numbers) are computed here in Python and baked into the kernels as compile-time constants; the two
dimensions the sampler uses have closed forms (bit reversal; the Pascal matrix mod 2), so a get2d
costs a few dozen integer operations and three hashes.

get1d(state, dim) equals get2d(state, dim).x: as everywhere in the renderer, one dimension id
serves one decision (see `renderer.sampling.dims`).

`reference_*` functions are a numpy model of the same arithmetic that the tests check the
kernels against bit for bit.
"""
import numpy as np
import taichi as ti

from renderer.sampling.rng import SampleState, pcg_hash

_INV_2_24 = 1.0 / 16777216.0

# Joe and Kuo (2008, new-joe-kuo-6.21201) primitive polynomials and initial direction numbers for
# Sobol dimensions 1..3 as (degree s, coefficients a, initial m_1..m_s); dimension 0 is the van der
# Corput sequence (the identity generator matrix, bit-reversed).
_JOE_KUO = ((1, 0, (1,)), (2, 1, (1, 3)), (3, 1, (1, 3, 1)))
N_DIMS = 1 + len(_JOE_KUO)
BITS = 32


def sobol_directions(n_dims: int = N_DIMS) -> np.ndarray:
    """(n_dims, 32) uint32: row d holds the direction numbers v_1..v_32 of Sobol dimension d, as
    32-bit fixed-point fractions (column `bit` of the generator matrix, applied to index bit `bit`)."""
    if not 1 <= n_dims <= N_DIMS:
        raise ValueError(f"n_dims must be in 1..{N_DIMS}")
    out = np.zeros((n_dims, BITS), dtype=np.uint64)
    out[0] = [1 << (BITS - 1 - k) for k in range(BITS)]
    for d in range(1, n_dims):
        s, a, m_init = _JOE_KUO[d - 1]
        m = list(m_init)
        for i in range(s, BITS):
            # m_i = 2^s m_{i-s} ^ m_{i-s} ^ sum_k 2^k a_k m_{i-k}, with a_k bit (s-1-k) of a.
            value = (m[i - s] << s) ^ m[i - s]
            for k in range(1, s):
                if (a >> (s - 1 - k)) & 1:
                    value ^= m[i - k] << k
            m.append(value)
        out[d] = [m[k] << (BITS - 1 - k) for k in range(BITS)]
    return out.astype(np.uint32)


# Python ints, so that `ti.u32(...)` bakes each one into the kernels as a constant.
DIRECTIONS = tuple(tuple(int(v) for v in row) for row in sobol_directions())

# Salts that derive the three scramble seeds of one decision from its dimension seed.
_DIM_STEP = 0x85EBCA6B  # odd: dimension ids map to distinct offsets of the key
_X_SALT = 0xA511E9B3
_Y_SALT = 0x63D83595
_PIXEL_SALT = 0x9E3779B9


@ti.func
def reverse_bits(v):
    x = ti.cast(v, ti.u32)
    x = ((x >> ti.u32(1)) & ti.u32(0x55555555)) | ((x & ti.u32(0x55555555)) << ti.u32(1))
    x = ((x >> ti.u32(2)) & ti.u32(0x33333333)) | ((x & ti.u32(0x33333333)) << ti.u32(2))
    x = ((x >> ti.u32(4)) & ti.u32(0x0F0F0F0F)) | ((x & ti.u32(0x0F0F0F0F)) << ti.u32(4))
    x = ((x >> ti.u32(8)) & ti.u32(0x00FF00FF)) | ((x & ti.u32(0x00FF00FF)) << ti.u32(8))
    return (x >> ti.u32(16)) | (x << ti.u32(16))


@ti.func
def lk_permutation(v, seed):
    """A hash in the Laine-Karras family: output bit k = input bit k XOR f(bits below k, seed), so
    on bit-reversed input it is a nested uniform scramble. These are the improved constants of
    N. Vegdahl, "Building a better LK hash" (2021), which follow Burley's construction and fix
    the original constants' weak mixing of the high bits."""
    x = ti.cast(v, ti.u32)
    s = ti.cast(seed, ti.u32)
    x ^= x * ti.u32(0x3D20ADEA)
    x += s
    x *= (s >> ti.u32(16)) | ti.u32(1)
    x ^= x * ti.u32(0x05526C56)
    x ^= x * ti.u32(0x53A22864)
    return x


@ti.func
def owen_scramble(v, seed):
    """Nested uniform (Owen) scramble of the 32 bits of v, most significant bit first."""
    return reverse_bits(lk_permutation(reverse_bits(v), seed))


@ti.func
def pascal_superset_xor(v):
    """Bit j of the result = XOR of the bits k of v whose positions are supersets of j (k & j == j).

    Sobol dimension 1's generator matrix is the Pascal matrix mod 2 (binomial(k, j) is odd iff
    k & j == j, by Lucas' theorem), so sobol_1(i) = reverse_bits(pascal_superset_xor(i)): five
    butterfly steps instead of 32 matrix columns."""
    x = ti.cast(v, ti.u32)
    x ^= (x >> ti.u32(1)) & ti.u32(0x55555555)
    x ^= (x >> ti.u32(2)) & ti.u32(0x33333333)
    x ^= (x >> ti.u32(4)) & ti.u32(0x0F0F0F0F)
    x ^= (x >> ti.u32(8)) & ti.u32(0x00FF00FF)
    x ^= (x >> ti.u32(16)) & ti.u32(0x0000FFFF)
    return x


@ti.func
def sobol_u32(index, d: ti.template()):
    """Sobol dimension d (0..3) of an index, as a 32-bit fraction: XOR of the generator matrix
    columns of the set index bits (unrolled over the 32 bits, branch-free); dimensions 0 and 1
    have closed forms."""
    i = ti.cast(index, ti.u32)
    x = ti.u32(0)
    if ti.static(d == 0):
        x = reverse_bits(i)
    elif ti.static(d == 1):
        x = reverse_bits(pascal_superset_xor(i))
    else:
        for bit in ti.static(range(BITS)):
            mask = ti.u32(0) - ((i >> ti.u32(bit)) & ti.u32(1))
            x ^= ti.u32(DIRECTIONS[d][bit]) & mask
    return x


@ti.func
def to_unit(x):
    """Top 24 bits as a float in [0, 1): exact in f32, so never rounded up to 1.0."""
    return ti.cast(x >> ti.u32(8), ti.f32) * _INV_2_24


@ti.data_oriented
class SobolSampler:
    """Shuffled, Owen-scrambled Sobol (0,2)-sequence per dimension id (see the module docstring)."""

    name = "sobol"

    @ti.func
    def start(self, pixel, index, seed):
        s = ti.cast(seed, ti.u32)
        # The key depends on the pixel and seed only: the sample index is shuffled per decision,
        # never hashed, or the samples of a pixel would stop forming one sequence.
        key = pcg_hash(pcg_hash(s ^ ti.u32(_PIXEL_SALT)) ^ ti.cast(pixel, ti.u32))
        return SampleState(pixel=ti.cast(pixel, ti.u32), index=ti.cast(index, ti.u32), seed=s, key=key)

    @ti.func
    def _dim_seed(self, state, dim):
        # One hash of (pixel key, dimension): the key is already a hash, and the odd multiplier
        # keeps the ids of a sample distinct (a hash of a hash of dim cost 1.3% of a Cornell box
        # sample more, to no benefit).
        return pcg_hash(state.key + ti.cast(dim, ti.u32) * ti.u32(_DIM_STEP))

    @ti.func
    def get1d(self, state, dim):
        ds = self._dim_seed(state, dim)
        j = owen_scramble(state.index, ds)
        # owen(sobol_0(j)) = reverse(LK(reverse(reverse(j)))) = reverse(LK(j)).
        return to_unit(reverse_bits(lk_permutation(j, pcg_hash(ds ^ ti.u32(_X_SALT)))))

    @ti.func
    def get2d(self, state, dim):
        ds = self._dim_seed(state, dim)
        j = owen_scramble(state.index, ds)
        x = reverse_bits(lk_permutation(j, pcg_hash(ds ^ ti.u32(_X_SALT))))
        # owen(sobol_1(j)) = reverse(LK(reverse(reverse(pascal(j))))) = reverse(LK(pascal(j))).
        y = reverse_bits(lk_permutation(pascal_superset_xor(j), pcg_hash(ds ^ ti.u32(_Y_SALT))))
        return ti.math.vec2(to_unit(x), to_unit(y))


# --- numpy reference (uint32 arrays; wrap-around arithmetic like the kernels) ------------------------
def _wrapping(fn):
    """uint32 arithmetic wraps like the kernels'; numpy only warns about it on 0-d values."""
    def wrapped(*args):
        with np.errstate(over="ignore"):
            return fn(*args)

    wrapped.__name__, wrapped.__doc__ = fn.__name__, fn.__doc__
    return wrapped


def _u32(v):
    return (np.asarray(v, dtype=np.int64) & 0xFFFFFFFF).astype(np.uint32)


@_wrapping
def reference_pcg_hash(v):
    state = _u32(v) * np.uint32(747796405) + np.uint32(2891336453)
    word = ((state >> ((state >> np.uint32(28)) + np.uint32(4))) ^ state) * np.uint32(277803737)
    return (word >> np.uint32(22)) ^ word


def reference_reverse_bits(v):
    x = _u32(v)
    for shift, mask in ((1, 0x55555555), (2, 0x33333333), (4, 0x0F0F0F0F), (8, 0x00FF00FF)):
        m, s = np.uint32(mask), np.uint32(shift)
        x = ((x >> s) & m) | ((x & m) << s)
    return (x >> np.uint32(16)) | (x << np.uint32(16))


@_wrapping
def reference_owen_scramble(v, seed):
    x = reference_reverse_bits(v)
    s = _u32(seed)
    x = x ^ (x * np.uint32(0x3D20ADEA))
    x = x + s
    x = x * ((s >> np.uint32(16)) | np.uint32(1))
    x = x ^ (x * np.uint32(0x05526C56))
    x = x ^ (x * np.uint32(0x53A22864))
    return reference_reverse_bits(x)


def reference_sobol_u32(index, d):
    i = _u32(index)
    x = np.zeros_like(i)
    for bit in range(BITS):
        x = x ^ np.where((i >> np.uint32(bit)) & np.uint32(1), np.uint32(DIRECTIONS[d][bit]), np.uint32(0))
    return x


@_wrapping
def _reference_seeds(pixel, dim, seed):
    key = reference_pcg_hash(reference_pcg_hash(_u32(seed) ^ np.uint32(_PIXEL_SALT)) ^ _u32(pixel))
    ds = reference_pcg_hash(key + _u32(dim) * np.uint32(_DIM_STEP))
    return ds, reference_pcg_hash(ds ^ np.uint32(_X_SALT)), reference_pcg_hash(ds ^ np.uint32(_Y_SALT))


def _reference_unit(x):
    return ((x >> np.uint32(8)).astype(np.float64) * _INV_2_24).astype(np.float32)


def reference_get2d(pixel, index, dim, seed):
    """What SobolSampler.get2d returns, for broadcastable integer arrays; shape (..., 2) float32."""
    ds, sx, sy = _reference_seeds(pixel, dim, seed)
    j = reference_owen_scramble(index, ds)
    x = reference_owen_scramble(reference_sobol_u32(j, 0), sx)
    y = reference_owen_scramble(reference_sobol_u32(j, 1), sy)
    return np.stack(np.broadcast_arrays(_reference_unit(x), _reference_unit(y)), axis=-1)


def reference_get1d(pixel, index, dim, seed):
    """What SobolSampler.get1d returns (the x of get2d with the same arguments)."""
    return reference_get2d(pixel, index, dim, seed)[..., 0]

"""Lane arithmetic: one value per ray of a packet, as a Taichi vector whose components LLVM's SLP
vectoriser turns into 8-lane (AVX2) or 16-lane (AVX-512) instructions on the CPU.

Taichi runs one loop index per iteration and never vectorises across iterations, so the packet
code puts the rays of a packet in the components of vectors (structure of arrays: a 3-vector of
rays is three lane vectors) and writes every step branch-free: both sides computed, the result
chosen with ti.select, finished rays masked. A branch on a per-lane value splits the code into
one block per lane and leaves it scalar; a branch on a value common to the packet (any lane
alive, a node any lane enters) keeps it vector and skips work for all lanes at once.

Masks are i32 lanes of 0 and 1 (Taichi's comparisons give u1, which its reductions do not take).
Functions here take their width from their arguments (x.n), so one definition serves any width.
"""
import math

import taichi as ti

PI = math.pi


def float_lanes(width: int):
    return ti.types.vector(width, ti.f32)


def int_lanes(width: int):
    return ti.types.vector(width, ti.i32)


def uint_lanes(width: int):
    return ti.types.vector(width, ti.u32)


@ti.func
def mask(condition):
    """A condition's lanes as i32 0 / 1."""
    return ti.select(condition, 1, 0)


@ti.func
def any_lane(m):
    """Whether any lane of the i32 mask m is set (a value common to the packet: branch on it)."""
    return m.max() > 0


@ti.func
def dot(ax, ay, az, bx, by, bz):
    return ax * bx + ay * by + az * bz


@ti.func
def normalized(x, y, z):
    inv = 1.0 / ti.sqrt(x * x + y * y + z * z)
    return x * inv, y * inv, z * inv


@ti.func
def pick(k, x, y, z):
    """Per lane, the component k (0, 1, 2) of (x, y, z): selects, not a dynamic index (which would
    spill the vectors to the stack)."""
    return ti.select(k == 0, x, ti.select(k == 1, y, z))


@ti.func
def kept(x, zero):
    """x unchanged, but opaque to floating-point reassociation and contraction: each lane's bits
    pass an integer OR with `zero` (0 at run time, not known to be at compile time), as
    triangle_packets._kept does for its four triangles."""
    out = x
    for c in ti.static(range(x.n)):
        out[c] = ti.bit_cast(ti.bit_cast(x[c], ti.i32) | zero, ti.f32)
    return out


@ti.func
def sincos_2pi(u):
    """(sin 2 pi u, cos 2 pi u) for u in [0, 1], lane by lane, by polynomials: ti.sin and ti.cos
    are libm calls, one per lane, that stop the vectoriser. The angle is taken to [-pi/2, pi/2]
    by symmetry, where the Taylor series to x^13 (sine) and x^12 (cosine) truncate below 1e-8; in
    f32 the results are within 2.6e-7 (sine) and 3.6e-7 (cosine) of numpy's over 65,536 uniform
    u (the f32 rounding of 2 pi u and of the sums; tests/packets/test_lanes.py holds them to 1e-6)."""
    x = 2.0 * PI * (u - 0.5)  # in [-pi, pi]: sin 2 pi u = -sin x, cos 2 pi u = -cos x
    folded = ti.abs(x) > 0.5 * PI
    r = ti.select(folded, ti.select(x > 0.0, PI - x, -PI - x), x)  # sin r = sin x; cos r = +-cos x
    r2 = r * r
    s = r * (1.0 + r2 * (-1.0 / 6.0 + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 * (
        1.0 / 362880.0 + r2 * (-1.0 / 39916800.0 + r2 * (1.0 / 6227020800.0)))))))
    c = 1.0 + r2 * (-0.5 + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 * (
        1.0 / 40320.0 + r2 * (-1.0 / 3628800.0 + r2 * (1.0 / 479001600.0))))))
    return -s, -ti.select(folded, -c, c)


@ti.func
def basis(nx, ny, nz):
    """An orthonormal basis (tx, ty, tz, bx, by, bz) about the unit normal n, branch-free (Duff et
    al. 2017)."""
    sign = ti.select(nz >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    return 1.0 + sign * nx * nx * a, sign * b, -sign * nx, b, sign + ny * ny * a, -ny


@ti.func
def cosine_hemisphere(u1, u2, nx, ny, nz):
    """Cosine-weighted directions about n (unit): (x, y, z, cos theta)."""
    r = ti.sqrt(u1)
    s, c = sincos_2pi(u2)
    lx = r * c
    ly = r * s
    lz = ti.sqrt(ti.max(1.0 - u1, 0.0))
    tx, ty, tz, bx, by, bz = basis(nx, ny, nz)
    return lx * tx + ly * bx + lz * nx, lx * ty + ly * by + lz * ny, lx * tz + ly * bz + lz * nz, lz


@ti.func
def _offset_axis(p, n):
    """intersect.offset_ray_origin for one coordinate of every lane."""
    of = ti.cast(256.0 * n, ti.i32)
    step = ti.select(p < 0.0, -of, of)
    moved = p
    for c in ti.static(range(p.n)):
        moved[c] = ti.bit_cast(ti.bit_cast(p[c], ti.i32) + step[c], ti.f32)
    return ti.select(ti.abs(p) < (1.0 / 32.0), p + (1.0 / 65536.0) * n, moved)


@ti.func
def offset_origin(px, py, pz, nx, ny, nz):
    """intersect.offset_ray_origin lane by lane: p moved off its surface along n by a few ulps of
    its own magnitude (Waechter and Binder 2019)."""
    return _offset_axis(px, nx), _offset_axis(py, ny), _offset_axis(pz, nz)


@ti.func
def seeded(x, j):
    """x, after storing its lanes side by side in a local array of which lane j (a run-time value)
    is read: LLVM's SLP vectoriser starts from runs of consecutive stores, and without them it
    left most lane arithmetic scalar (a whole packet path had 633 scalar, 618 4-lane and 214
    8-lane float operations); the dynamic read keeps the stores from being optimised away, as
    wide_traversal's node keys are kept. Returns (x, the lane read) for the caller to keep."""
    keep = x * 0.0
    for c in ti.static(range(x.n)):
        keep[c] = x[c]
    return x, keep[j]

"""One primitive against every ray of a packet: the scalar tests of renderer/geometry/intersect.py,
operation for operation, with each ray a lane (so a packet's decisions are the scalar test's,
ray by ray). Every test returns (hit mask, t, b1, b2) lanes; a lane hits only in (0, t_max), so a
lane whose t_max is negative (finished, or not a ray) never hits."""
import taichi as ti

from renderer.packets.lanes import kept, mask, pick


@ti.func
def watertight_setup(dx, dy, dz):
    """intersect.watertight_setup lane by lane: the axis permutation (kx, ky, kz) and shear
    (sx, sy, sz) of each ray."""
    ax, ay, az = ti.abs(dx), ti.abs(dy), ti.abs(dz)
    kz = ti.select((ax >= ay) & (ax >= az), 0, ti.select(ay >= az, 1, 2))
    kx = (kz + 1) % 3
    ky = (kx + 1) % 3
    dkz = pick(kz, dx, dy, dz)
    swap = dkz < 0.0
    kx, ky = ti.select(swap, ky, kx), ti.select(swap, kx, ky)
    inv = 1.0 / dkz
    return kx, ky, kz, pick(kx, dx, dy, dz) * inv, pick(ky, dx, dy, dz) * inv, inv


@ti.func
def triangle(ox, oy, oz, kx, ky, kz, sx, sy, sz, v0, v1, v2, t_max, zero):
    """intersect.triangle_watertight of the corners v0, v1, v2 (vec3, the same for every lane).
    `zero`: an i32 0 the compiler cannot see; the corners' differences from the origin and the
    edge functions' products pass through it (lanes.kept) so that fast math neither reassociates
    the shear with them nor fuses one product into an FMA, which would round the two triangles
    of an edge differently and let rays through (triangle_packets has the measurements)."""
    ax, ay, az = kept(v0.x - ox, zero), kept(v0.y - oy, zero), kept(v0.z - oz, zero)
    bx, by, bz = kept(v1.x - ox, zero), kept(v1.y - oy, zero), kept(v1.z - oz, zero)
    cx, cy, cz = kept(v2.x - ox, zero), kept(v2.y - oy, zero), kept(v2.z - oz, zero)
    akz, bkz, ckz = pick(kz, ax, ay, az), pick(kz, bx, by, bz), pick(kz, cx, cy, cz)
    pax, pay = pick(kx, ax, ay, az) - sx * akz, pick(ky, ax, ay, az) - sy * akz
    pbx, pby = pick(kx, bx, by, bz) - sx * bkz, pick(ky, bx, by, bz) - sy * bkz
    pcx, pcy = pick(kx, cx, cy, cz) - sx * ckz, pick(ky, cx, cy, cz) - sy * ckz
    u = kept(pcx * pby, zero) - kept(pcy * pbx, zero)
    v = kept(pax * pcy, zero) - kept(pay * pcx, zero)
    w = kept(pbx * pay, zero) - kept(pby * pax, zero)
    neg = mask(u < 0.0) | mask(v < 0.0) | mask(w < 0.0)
    pos = mask(u > 0.0) | mask(v > 0.0) | mask(w > 0.0)
    det = u + v + w
    tt = u * (sz * akz) + v * (sz * bkz) + w * (sz * ckz)
    sign = ti.select(det > 0.0, 1.0, -1.0)
    hit = ((neg & pos) ^ 1) & mask(det != 0.0) & mask(tt * sign > 0.0) & mask(tt * sign < t_max * det * sign)
    inv = 1.0 / ti.select(det != 0.0, det, 1.0)
    return hit, tt * inv, v * inv, w * inv


@ti.func
def quad(ox, oy, oz, dx, dy, dz, corner, normal, u_dual, v_dual, t_max):
    """intersect.quad_framed: the plane's precomputed rows (normal and the edges' dual vectors)."""
    denom = normal.x * dx + normal.y * dy + normal.z * dz
    tt = (normal.x * (corner.x - ox) + normal.y * (corner.y - oy) + normal.z * (corner.z - oz)) / ti.select(
        denom != 0.0, denom, 1.0)
    px = ox + tt * dx - corner.x
    py = oy + tt * dy - corner.y
    pz = oz + tt * dz - corner.z
    a = px * u_dual.x + py * u_dual.y + pz * u_dual.z
    b = px * v_dual.x + py * v_dual.y + pz * v_dual.z
    hit = (mask(denom != 0.0) & mask(tt > 0.0) & mask(tt < t_max) & mask(a >= 0.0) & mask(a <= 1.0)
           & mask(b >= 0.0) & mask(b <= 1.0))
    return hit, tt, a, b


@ti.func
def sphere(ox, oy, oz, dx, dy, dz, center, radius, t_max):
    """intersect.sphere (Haines et al. 2019's stable form); unit directions."""
    fx, fy, fz = ox - center.x, oy - center.y, oz - center.z
    b = -(fx * dx + fy * dy + fz * dz)
    lx, ly, lz = fx + b * dx, fy + b * dy, fz + b * dz
    disc = radius * radius - (lx * lx + ly * ly + lz * lz)
    c = (fx * fx + fy * fy + fz * fz) - radius * radius
    root = ti.sqrt(ti.max(disc, 0.0))
    q = ti.select(b != 0.0, b + ti.select(b > 0.0, 1.0, -1.0) * root, root)
    t0 = ti.select(q != 0.0, c / ti.select(q != 0.0, q, 1.0), 0.0)
    near = ti.min(t0, q)
    far = ti.max(t0, q)
    take_near = mask(near > 0.0) & mask(near < t_max)
    take_far = mask(far > 0.0) & mask(far < t_max)
    hit = mask(disc >= 0.0) & (take_near | take_far)
    zero = ti.select(take_near == 1, near, far) * 0.0
    return hit, ti.select(take_near == 1, near, far), zero, zero

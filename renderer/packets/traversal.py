"""A packet of rays through the mesh world's wide BVH together (Wald et al. 2001's packet
traversal, on the wide nodes of renderer/geometry/wide_traversal.py).

The packet shares one stack and one walk: a node's child is entered when any live ray enters its
box, and each child box is tested against all rays at once, one lane a ray (the scalar traversal
instead tests one ray against the eight boxes of a node, one lane a box). A child's key is the
nearest entry of any ray; the nearest child is entered next and the others are pushed without a
branch, as the scalar visit does. A popped child is skipped when it lies beyond every ray's
closest hit so far. Leaves test their primitives one after another against every ray
(renderer/packets/primitives.py): a primitive is one for the whole packet, so which test to run
is a branch common to the packet. Rays a packet does not need (finished paths, lanes past the
image) enter with a negative t_max, which no box and no primitive accepts.

Shadow rays (any_hit) drop out as they find a blocker; the walk stops when none is left.

Supported: the wide traversals (wide4, wide8), scalar or packet leaves, triangles (watertight),
quads and spheres, no instances and no alpha coverage; renderer/packets/support.py checks that a
scene is within that before a packet program is made.
"""
import taichi as ti

from renderer.geometry.interface import Ray
from renderer.geometry.wide_traversal import MISS_KEY, nearest_child
from renderer.packets import primitives
from renderer.packets.lanes import any_lane, mask

PACKET_KINDS = frozenset({"triangle", "quad", "sphere"})


@ti.func
def _slot_prim(geometry: ti.template(), j):
    """The primitive in leaf slot j."""
    g = 0
    if ti.static(geometry.packed):
        g = geometry.packets.prims[j >> 2][j & 3]
    else:
        g = geometry.slot_prim[j]
    return g


@ti.func
def _test_prim(geometry: ti.template(), g, ox, oy, oz, dx, dy, dz, kx, ky, kz, sx, sy, sz, t_max, zero):
    """Primitive g against the packet: (hit mask, t, b1, b2) lanes, as MeshGeometry._test_prim."""
    hit = ti.select(t_max < 0.0, 0, 0)
    t = t_max * 0.0
    b1 = t
    b2 = t
    if ti.static("triangle" in geometry.kinds):
        if g < geometry.range_end[0]:
            v0, v1, v2 = geometry.corners_of(g)
            hit, t, b1, b2 = primitives.triangle(ox, oy, oz, kx, ky, kz, sx, sy, sz, v0, v1, v2, t_max, zero)
    if ti.static("sphere" in geometry.kinds):
        if g >= geometry.range_end[0] and g < geometry.range_end[1]:
            sp = geometry.spheres[g - geometry.range_end[0]]
            hit, t, b1, b2 = primitives.sphere(ox, oy, oz, dx, dy, dz, sp.xyz, sp.w, t_max)
    if ti.static("quad" in geometry.kinds):
        if g >= geometry.range_end[1] and g < geometry.range_end[2]:
            i = g - geometry.range_end[1]
            hit, t, b1, b2 = primitives.quad(ox, oy, oz, dx, dy, dz, geometry.quads[i, 0], geometry.quad_frames[i, 0],
                                             geometry.quad_frames[i, 1], geometry.quad_frames[i, 2], t_max)
    return hit, t, b1, b2


@ti.func
def trace(geometry: ti.template(), ox, oy, oz, dx, dy, dz, t_max, any_hit: ti.template()):
    """The packet's rays (origin and unit direction lanes, searched in (0, t_max); lanes with a
    negative t_max are not rays) through `geometry` (a MeshGeometry within PACKET_KINDS).
    Returns (prim, t, b1, b2, work) lanes and counts: the primitive each ray hits first (-1: none)
    and its barycentrics, or with any_hit the first blocker found (its t and barycentrics are
    then of no use); work = (node visits, primitive tests), one each per packet step."""
    wide = geometry.wide
    width = ti.static(geometry.wide.width)
    inv_x = 1.0 / ti.select(ti.abs(dx) > 1e-30, dx, 1e-30)
    inv_y = 1.0 / ti.select(ti.abs(dy) > 1e-30, dy, 1e-30)
    inv_z = 1.0 / ti.select(ti.abs(dz) > 1e-30, dz, 1e-30)
    # each ray's rows of near planes (wide_traversal.plane_rows): lo (0..2) where d >= 0
    near_x = ti.select(dx >= 0.0, 0, 3)
    near_y = ti.select(dy >= 0.0, 1, 4)
    near_z = ti.select(dz >= 0.0, 2, 5)
    kx, ky, kz, sx, sy, sz = primitives.watertight_setup(dx, dy, dz)
    zero = ti.cast(t_max[0] < -3.0e38, ti.i32)  # 0 at run time, unknown to the compiler (lanes.kept)
    t = t_max
    prim = ti.select(t_max < 0.0, -1, -1)
    b1 = t_max * 0.0
    b2 = b1
    live = mask(t_max >= 0.0)
    visits = 0
    tests = 0
    stack_ref = ti.Vector([0] * geometry.stack_size, dt=ti.i32)
    stack_t = ti.Vector([0.0] * geometry.stack_size, dt=ti.f32)
    sp = 0
    ref = 0  # the world's root node
    going = any_lane(live)
    while going:
        found = False
        if ref < 0:
            leaf = ~ref
            first = leaf >> wide.count_bits
            for j in range(first, first + (leaf & wide.count_mask)):
                g = _slot_prim(geometry, j)
                h, tt, u, v = _test_prim(geometry, g, ox, oy, oz, dx, dy, dz, kx, ky, kz, sx, sy, sz, t, zero)
                tests += 1
                t = ti.select(h == 1, tt, t)
                prim = ti.select(h == 1, g, prim)
                b1 = ti.select(h == 1, u, b1)
                b2 = ti.select(h == 1, v, b2)
                if ti.static(any_hit):
                    live &= h ^ 1
                    t = ti.select(h == 1, -1.0, t)  # a blocked ray takes no further part
            if ti.static(any_hit):
                if not any_lane(live):
                    break
        else:
            visits += 1
            # Each ray's test of the node's children is the scalar visit's (one lane a child:
            # WideNodes.child_keys), and a child's key is the nearest entry of any ray: no
            # horizontal reduction, and dead rays (t < 0) enter nothing.
            keys = ti.Vector([MISS_KEY] * width, dt=ti.f32)
            for k in ti.static(range(ox.n)):
                entry = wide.child_keys(ref, ti.math.vec3(ox[k], oy[k], oz[k]),
                                        ti.math.vec3(inv_x[k], inv_y[k], inv_z[k]),
                                        ti.math.ivec3(near_x[k], near_y[k], near_z[k]),
                                        ti.math.ivec3(near_x[k] + 3, near_y[k] + 3, near_z[k] + 3) % 6, t[k])
                keys = ti.select(entry < keys, entry, keys)
            nearest, best = nearest_child(keys)
            for i in ti.static(range(1, width)):
                c = (best + i) & (width - 1)
                key = keys[c]
                stack_ref[sp] = wide.child[ref, c]
                stack_t[sp] = key
                sp += ti.select(key < MISS_KEY, 1, 0)
            found = nearest < MISS_KEY
            ref = wide.child[ref, best]
        # pop, skipping children beyond every ray's closest hit
        farthest = t.max()
        while not found and sp > 0:
            sp -= 1
            if stack_t[sp] <= farthest:
                ref = stack_ref[sp]
                found = True
        going = found
    prim = ti.select(t_max < 0.0, -1, prim)
    return prim, t, b1, b2, visits, tests


@ti.func
def trace_lanes(geometry: ti.template(), ox, oy, oz, dx, dy, dz, t_max, any_hit: ti.template()):
    """`trace`'s answer, each ray through the scalar traversal on its own (one lane after another,
    lanes with a negative t_max skipped): for rays so incoherent that a packet's union of nodes
    costs more than its rays' own walks. Its work (node visits, primitive tests) is each ray's
    own, as float lanes, where `trace` counts the packet's steps once for all."""
    prim = ti.select(t_max < 0.0, -1, -1)
    t = t_max
    b1 = t_max * 0.0
    b2 = b1
    visits = t_max * 0.0
    tests = t_max * 0.0
    for k in range(ox.n):
        if t_max[k] >= 0.0:
            hit = geometry.trace(Ray(o=ti.math.vec3(ox[k], oy[k], oz[k]), d=ti.math.vec3(dx[k], dy[k], dz[k]),
                                     cone_width=0.0, cone_spread=0.0), t_max[k], any_hit)
            visits[k] = hit.work
            tests[k] = hit.tests
            if hit.hit == 1:
                prim[k] = hit.prim
                t[k] = hit.t
                b1[k] = hit.bary.x
                b2[k] = hit.bary.y
    return prim, t, b1, b2, visits, tests

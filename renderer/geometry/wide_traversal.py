"""The 4-wide (or 8-wide) BVH on the device (renderer/geometry/wide_bvh.py) and its ordered
traversal.

A visit tests the node's children together, written so that LLVM's SLP vectoriser turns the test
into 4-lane (8-lane) instructions on the CPU (docs/findings.md, "BVH traversal",
has the evidence; scripts/wide_bvh_ir.py shows it): every child's entry and exit distances and
the hit mask are computed unconditionally and folded into one key per child (its entry
distance, or MISS_KEY) before the first branch, and the keys are also stored to a local array
that a dynamic index reads (that store is what LLVM vectorises from). Only then is the nearest
child found (a tournament of compare-and-selects: 3 comparators for 4 keys, 7 for 8) and
entered next; the others are pushed without a branch, in slot order after the nearest, each
with its entry distance, the stack pointer moving only past those the ray entered, and skipped
on pop once a closer hit is known. Shadow rays stop at their first hit, as in the binary
traversals. (Sorting all the keys with a network and pushing under one branch per child, the
earlier code, visited 2-3 % fewer nodes but took longer a visit: the pushes' branches follow
the ray's random hit pattern on incoherent rays.)

A node's child boxes and child references share one cell of the node array (the two fields are
placed under one dense SNode, array-of-structures by node), so a visit reads one 112-byte
(4-wide) or 224-byte (8-wide) block instead of two separate arrays.

Per ray, each axis reads its near planes from the lo row (direction >= 0) or the hi row, and its
far planes from the other, so a slab test needs no min/max between t0 and t1, and an empty slot
(lo = +F32_MAX > hi = -F32_MAX) has its far planes behind every origin, so it is never entered.
The far distance is widened as in intersect.box_entry (Ize 2013). Minima and maxima are
compare-and-select: LLVM's minnum/maxnum would add two instructions each for NaN, which these
distances never are (the direction's zero components are replaced as in MeshGeometry).

Instances (the two-level BVH): an instance child, once entered, moves the ray into the
instance's frame and walks its mesh's wide tree from its root, above a stack marker that brings
the world ray back.
"""
import taichi as ti

from renderer.geometry.wide_bvh import WideBVH

MISS_KEY = 3.0e38  # a child's key when the ray does not enter it; above every t_max (INF = 1e30)
RESUME_WORLD = 2**31 - 1  # the stack entry below an instance's nodes (never a node index)
GROW_FAR = 1.00000024  # the far distance's widening, as intersect.box_entry's

ivec3 = ti.math.ivec3
vec4 = ti.math.vec4


@ti.func
def _min(a, b):
    """min for values that are never NaN: one vminps (ti.min adds a NaN check)."""
    return ti.select(a < b, a, b)


@ti.func
def _max(a, b):
    return ti.select(a > b, a, b)


@ti.func
def nearest_child(key):
    """(the smallest of the 4 or 8 keys, its slot): a tournament of compare-and-selects (the lower
    slot on a tie)."""
    width = ti.static(key.n)
    k = key
    s = ti.Vector([c for c in range(width)], dt=ti.i32)
    for level in ti.static(range(width.bit_length() - 1)):
        step = ti.static(1 << level)
        for i in ti.static(range(0, width, 2 * step)):
            later = k[i + step] < k[i]
            k[i] = ti.select(later, k[i + step], k[i])
            s[i] = ti.select(later, s[i + step], s[i])
    return k[0], s[0]


@ti.func
def plane_rows(d):
    """Rows of the near and far planes of each axis for direction d: lo (0..2) where d >= 0."""
    near = ivec3(0, 1, 2)
    for a in ti.static(range(3)):
        near[a] = a if d[a] >= 0.0 else a + 3
    return near, (near + 3) % 6


@ti.data_oriented
class WideNodes:
    """The wide nodes on the device: child boxes as (node, row) vec4s, one lane per child, and
    each child as one packed i32 (WideBVH.packed_refs: a node >= 0, or a leaf or an instance)."""

    def __init__(self, wide: WideBVH, uploads: list):
        """Appends its (field, array) pairs to `uploads` (one launch for the whole mesh)."""
        if wide.num_nodes >= RESUME_WORLD:
            raise ValueError("the wide BVH has too many nodes for i32 references")
        self.count = wide.num_nodes
        self.width = wide.width
        refs, self.count_bits = wide.packed_refs()
        self.count_mask = (1 << self.count_bits) - 1
        self.bounds = ti.Vector.field(self.width, ti.f32)
        self.child = ti.field(ti.i32)
        node = ti.root.dense(ti.i, self.count)  # one cell a node: its bounds, then its references
        node.dense(ti.j, 6).place(self.bounds)
        node.dense(ti.j, self.width).place(self.child)
        uploads += [(self.bounds, wide.bounds), (self.child, refs)]

    @staticmethod
    def bytes_per_node(width: int) -> int:
        """Six rows of child bounds and a reference per child."""
        return 6 * width * 4 + width * 4

    def device_bytes(self) -> int:
        return self.count * self.bytes_per_node(self.width)

    @ti.func
    def child_keys(self, node, o, inv_d, near, far, t_max):
        """Each child's entry distance if the ray (origin o, 1 / direction inv_d) enters its box
        before t_max, else MISS_KEY; all lanes at once, no branch."""
        tnx = (self.bounds[node, near.x] - o.x) * inv_d.x
        tny = (self.bounds[node, near.y] - o.y) * inv_d.y
        tnz = (self.bounds[node, near.z] - o.z) * inv_d.z
        tfx = (self.bounds[node, far.x] - o.x) * inv_d.x
        tfy = (self.bounds[node, far.y] - o.y) * inv_d.y
        tfz = (self.bounds[node, far.z] - o.z) * inv_d.z
        tn = _max(_max(tnx, tny), _max(tnz, 0.0))
        tf = _min(_min(tfx, tfy), _min(tfz, t_max)) * GROW_FAR
        return ti.select(tn <= tf, tn, MISS_KEY)

    @ti.func
    def visit(self, node, o, inv_d, near, far, t_max, stack_ref: ti.template(), stack_t: ti.template(), sp):
        """Test node's children; push every entered one but the nearest (no branch).
        Returns (the nearest entered child's ref, whether there is one, the new stack size)."""
        entry = self.child_keys(node, o, inv_d, near, far, t_max)
        # The keys also go to a local array read by a dynamic index below: its four stores become
        # one 4-lane store, from which LLVM vectorises the node test 4 lanes wide. Without it, or
        # with other code after the test, it chose 2 lanes.
        keys = ti.Vector([MISS_KEY] * self.width, dt=ti.f32)
        for c in ti.static(range(self.width)):
            keys[c] = entry[c]
        nearest, best = nearest_child(entry)
        # Every other slot is written; sp moves past the entered ones only, so a missed child's
        # entry is overwritten by the next push. The writes stay within stack_size(): a visit
        # writes at most width - 2 entries past its entered ones.
        for i in ti.static(range(1, self.width)):
            c = (best + i) & (self.width - 1)
            key = keys[c]
            stack_ref[sp] = self.child[node, c]
            stack_t[sp] = key
            sp += ti.select(key < MISS_KEY, 1, 0)
        return self.child[node, best], nearest < MISS_KEY, sp

    @ti.func
    def traverse(self, geometry: ti.template(), ray, hit: ti.template(), any_hit):
        """Into `hit` (a fresh Hit whose t is the ray's t_max): the closest hit, or (any_hit: a
        constant or a per-ray value) the first hit found, of ray in geometry (a MeshGeometry: its
        leaf test, ray constants, stack size and instances)."""
        o = ray.o
        d = ray.d
        inv_d, k, s = geometry._ray_setup(d)
        near, far = plane_rows(d)
        instance = -1  # the instance whose frame o, d are in; -1: the world
        stack_ref = ti.Vector([0] * geometry.stack_size, dt=ti.i32)
        stack_t = ti.Vector([0.0] * geometry.stack_size, dt=ti.f32)
        sp = 0
        ref = 0  # the current child: the world's root node
        going = True
        while going:
            if ti.static(geometry.has_instances):
                if ref < 0 and (~ref & self.count_mask) == 0:
                    # an instance whose box was entered: walk its mesh's tree in its frame
                    instance = ~ref >> self.count_bits
                    o, d = geometry.instances.ray_to_object(instance, ray.o, ray.d)
                    inv_d, k, s = geometry._ray_setup(d)
                    near, far = plane_rows(d)
                    stack_ref[sp] = RESUME_WORLD
                    stack_t[sp] = -1.0
                    sp += 1
                    ref = geometry.instances.root[instance]
            found = False
            if ref < 0:
                leaf = ~ref
                geometry.test_leaf(leaf >> self.count_bits, leaf & self.count_mask, o, d, k, s, hit, any_hit, ray,
                                   instance)
                if any_hit:
                    if hit.hit == 1:
                        break
            else:
                hit.work += 1
                ref, found, sp = self.visit(ref, o, inv_d, near, far, hit.t, stack_ref, stack_t, sp)
            # pop, skipping children whose entry lies beyond the closest hit found since the push
            while not found and sp > 0:
                sp -= 1
                take = stack_t[sp] <= hit.t
                if ti.static(geometry.has_instances):
                    if stack_ref[sp] == RESUME_WORLD:  # back in the world
                        instance = -1
                        o = ray.o
                        d = ray.d
                        inv_d, k, s = geometry._ray_setup(d)
                        near, far = plane_rows(d)
                        take = False
                if take:
                    ref = stack_ref[sp]
                    found = True
            going = found


def stack_size(wide: WideBVH) -> int:
    """Stack entries the traversal needs: the world's levels and the deepest mesh's, width - 1
    siblings each, and the marker below an instance's nodes."""
    meshes = int(wide.depth[1:].max()) if len(wide.depth) > 1 else 0
    return (wide.width - 1) * (int(wide.depth[0]) + meshes) + 1

"""The mesh side of the geometry interface: triangles, analytic spheres, quads and discs, and
Bezier surfaces of revolution (patches, bezier_device.py) in one BVH, traversed on the device.

Four traversals (a compile-time choice, benchmarked against each other):
  "stack":     ordered traversal; both children's boxes are tested, the nearer visited first, the
               farther pushed with its entry distance and skipped on pop once a closer hit is known.
  "stackless": the depth-first next-pointer ("miss link") walk: no stack, no ordering.
  "wide4":     the binary tree collapsed into 4-wide nodes (renderer/geometry/wide_bvh.py), whose
               four child boxes are tested together; the nearest entered child is visited next,
               the others pushed with their entry distances (wide_traversal.py).
  "wide8":     the same with 8-wide nodes; the Renderer's default (MeshOptions).
Two triangle tests: "watertight" (Woop et al. 2013, the default) and "moller" (Moller-Trumbore).
Two leaf layouts: "scalar" (a leaf's primitives tested one by one from the slot array) and
"packets" (four slots at a time, triangles structure-of-arrays: triangle_packets.py).
Only the primitive kinds the scene has are compiled in, and each of these only where the scene
needs it: vertex colours, alpha coverage (renderer/geometry/coverage.py, which needs the material
table) and instances (a two-level BVH, renderer/geometry/instance_bvh.py: on entering an instance
node the ray moves into the instance's frame, its mesh's tree is walked in the same loop, and the
world ray comes back on leaving it; renderer/geometry/instances.py).
"""
import numpy as np
import taichi as ti

from renderer.geometry import coverage
from renderer.geometry import emitter_shapes as shapes
from renderer.geometry import intersect as isect
from renderer.geometry.instance_bvh import INSTANCE_NODE, InstancedBVH
from renderer.geometry.instances import InstanceTable
from renderer.geometry.interface import INF, EmitterPoint, Hit, Ray, Surface, owners_of
from renderer.geometry.mesh_data import MeshData
from renderer.geometry.shading import consistent_shading_normal
from renderer.geometry.triangle_packets import TrianglePackets, build_packets, nearest_lane, permuted_origin
from renderer.geometry.texture_footprint import uv_footprint
from renderer.geometry.uv_partials import barycentric_partials, sphere_uv_partials, triangle_uv_partials, uv_area
from renderer.geometry.wide_bvh import collapse, empty_wide_bvh
from renderer.geometry.wide_traversal import WideNodes, stack_size
from renderer.materials.kinds import BACK_CULLED
from renderer.materials.mapped_frame_rows import needs_uv_partials
from renderer.materials.table import ALPHA_OPAQUE
from renderer.runtime.upload import upload_fields

vec3 = ti.math.vec3
STACK_SIZE = 64  # deeper than any tree the builder makes (its depth is bounded well below this)
RESUME_WORLD = -2  # the stack entry below an instance's nodes: the world ray comes back there
TRAVERSALS = ("stack", "stackless", "wide4", "wide8")
WIDE_TRAVERSALS = {"wide4": 4, "wide8": 8}  # traversal -> node width
TRIANGLE_TESTS = ("watertight", "moller")
LEAF_LAYOUTS = ("scalar", "packets")


@ti.data_oriented
class MeshGeometry:
    kind = "mesh"

    def __init__(self, data: MeshData, bvh, traversal="stack", triangle_test="watertight", materials=None,
                 leaves="scalar"):
        """bvh: instance_bvh.build_scene_bvh's result for `data` (a FlatBVH where the data has no
        instances). materials: the MaterialTable, needed where a material uses alpha coverage."""
        if traversal not in TRAVERSALS:
            raise ValueError(f"unknown traversal '{traversal}' (choose from {', '.join(TRAVERSALS)})")
        if triangle_test not in TRIANGLE_TESTS:
            raise ValueError(f"unknown triangle test '{triangle_test}' (choose from {', '.join(TRIANGLE_TESTS)})")
        if leaves not in LEAF_LAYOUTS:
            raise ValueError(f"unknown leaf layout '{leaves}' (choose from {', '.join(LEAF_LAYOUTS)})")
        self.traversal = traversal
        self.triangle_test = triangle_test
        self.packed = leaves == "packets"
        self.kinds = data.kinds()
        self.has_other_kinds = bool(self.kinds - {"triangle"})  # (packets test those lane by lane)
        self.has_normals = data.tri_normals is not None and len(data.tri_vertices) > 0
        self.has_uvs = data.tri_uvs is not None and len(data.tri_vertices) > 0
        self.has_uv1 = data.tri_uvs1 is not None and len(data.tri_vertices) > 0
        self.has_tangents = data.tri_tangents is not None and len(data.tri_vertices) > 0
        self.has_colors = data.tri_colors is not None and len(data.tri_vertices) > 0
        self.materials = materials
        # Coverage is tested in traversal for alpha (glTF MASK / BLEND, Mitsuba's mask) and back-face culling.
        self.has_alpha, self.has_uv_partials = self._material_flags(materials.arrays if materials is not None
                                                                    else None)
        # Mip-mapped textures: hits carry the pixel's footprint in texture coordinates (and the
        # dp/du, dp/dv it is measured with).
        self.filters_textures = materials is not None and materials.textures.filters
        self.needs_partials = self.has_uv_partials or self.filters_textures
        self.has_instances = data.has_instances
        # Spheres or quads with their normals turned over (Mitsuba's flip_normals): a sign per
        # analytic primitive, compiled in only where one is.
        self.has_flipped = data.has_flipped
        self.stack_size = STACK_SIZE
        if self.has_instances:
            if not isinstance(bvh, InstancedBVH):
                raise ValueError("mesh data with instances needs the two-level BVH of build_scene_bvh")
            self.stack_size = max(STACK_SIZE, bvh.stack_depth)
        nodes = bvh.nodes if self.has_instances else bvh
        self.node_total = len(nodes.node_count)
        self.data = data  # kept for emitter_info (the device has its own copy)
        uploads = []  # (field, array): copied in one launch (renderer.runtime.upload)
        mesh_root = bvh.mesh_root if self.has_instances else np.zeros(0, np.int32)
        if traversal in WIDE_TRAVERSALS:
            mesh_root, prim_order = self._upload_wide(nodes, mesh_root, uploads, WIDE_TRAVERSALS[traversal])
        else:
            prim_order = self._upload_bvh(nodes, uploads)
        self._upload_slots(data, prim_order, uploads)
        self._upload_primitives(data, nodes, uploads)
        if self.has_instances:
            self.instances = InstanceTable(mesh_root[data.instance_mesh], data.instance_to_world, uploads)
        upload_fields(uploads)

    # --- upload --------------------------------------------------------------------------------
    def _upload_bvh(self, bvh, uploads):
        m = max(1, self.node_total)
        self.node_lo = ti.Vector.field(3, ti.f32, shape=m)
        self.node_hi = ti.Vector.field(3, ti.f32, shape=m)
        self.node_link = ti.Vector.field(3, ti.i32, shape=m)  # (right child | first prim, count, skip)
        if self.node_total:
            uploads += [(self.node_lo, bvh.node_lo), (self.node_hi, bvh.node_hi),
                        (self.node_link, np.stack([bvh.node_a, bvh.node_count, bvh.node_skip], axis=1))]
        else:  # an empty box no ray can enter
            uploads += [(self.node_lo, np.full((1, 3), 1e30)), (self.node_hi, np.full((1, 3), -1e30))]
        return bvh.prim_order

    def _upload_wide(self, bvh, mesh_root, uploads, width):
        """The binary tree collapsed into wide nodes, uploaded; returns the wide root of each
        instanced mesh's tree and the primitive order."""
        wide = (collapse(bvh, np.concatenate([[0], mesh_root]), width) if self.node_total
                else empty_wide_bvh(width))
        self.node_total = wide.num_nodes
        self.stack_size = stack_size(wide)
        self.wide = WideNodes(wide, uploads)
        return wide.roots[1:], wide.prim_order

    def _upload_slots(self, data: MeshData, prim_order, uploads):
        """The leaves' primitives: the slot array and the triangles' corners, or the packets
        that hold both."""
        if self.packed:
            self.packets = TrianglePackets(build_packets(prim_order, data.tri_vertices), uploads)
            return
        self.slot_prim = ti.field(ti.i32, shape=max(1, len(prim_order)))
        if len(prim_order):
            uploads.append((self.slot_prim, prim_order))
        t = len(data.tri_vertices)
        self.tri_v = ti.Vector.field(3, ti.f32, shape=(max(1, t), 3))
        if t:
            uploads.append((self.tri_v, data.tri_vertices))

    def _upload_primitives(self, data: MeshData, bvh, uploads):
        def vec_field(n, array, width=3, rows=()):
            f = ti.Vector.field(width, ti.f32, shape=(max(1, n), *rows))
            if n:
                uploads.append((f, array))
            return f

        t = len(data.tri_vertices)
        if self.has_normals:
            self.tri_n = vec_field(t, data.tri_normals, 3, (3,))
        if self.has_uvs:
            self.tri_uv = vec_field(t, data.tri_uvs, 2, (3,))
        if self.has_uv1:
            self.tri_uv1 = vec_field(t, data.tri_uvs1, 2, (3,))
        if self.has_tangents:
            self.tri_tangent = vec_field(t, data.tri_tangents, 4, (3,))
        if self.has_colors:
            self.tri_color = vec_field(t, data.tri_colors, 4, (3,))
        self.spheres = vec_field(len(data.spheres), data.spheres, 4)
        self.sphere_frames = vec_field(len(data.spheres), data.sphere_axes(), 3, (3,))
        self.quads = vec_field(len(data.quads), data.quads, 3, (3,))
        self.quad_frames = vec_field(len(data.quads), isect.quad_frames(data.quads), 3, (3,))
        discs = data.discs
        self.discs_a = vec_field(len(discs), discs[:, [0, 1, 2, 6]], 4)  # centre xyz, radius
        self.discs_n = vec_field(len(discs), discs[:, 3:6], 3)
        materials = data.materials()
        self.prim_material = ti.field(ti.i32, shape=max(1, len(materials)))
        if len(materials):
            uploads.append((self.prim_material, materials))
        self.range_end = ti.field(ti.i32, shape=5)
        uploads.append((self.range_end, data.range_ends()))
        if self.has_flipped:  # 1 where a sphere's or quad's normal is turned over, from the first sphere
            flipped = data.analytic_flipped()
            self.flipped = ti.field(ti.i32, shape=len(flipped))
            uploads.append((self.flipped, flipped))
        if "bezier" in self.kinds:  # only then: other scenes never see (or compile) Bezier code
            from renderer.geometry.bezier_device import BezierPatches

            self.bezier = BezierPatches(data, uploads)

    def device_bytes(self) -> dict:
        """Bytes on the device: the BVH (every level), the triangles' intersection data, their
        shading attributes (normals, texture coordinates, tangents, colours), the instance table,
        and the total of these with the other primitives and the material ids."""
        nodes = self.wide.device_bytes() if self.traversal in WIDE_TRAVERSALS else self.node_total * (12 + 12 + 12)
        if self.packed:
            packets = self.packets.device_bytes()
            slots, triangles = packets["ids"], packets["triangles"]
        else:
            slots, triangles = self.slot_prim.shape[0] * 4, self.tri_v.shape[0] * 36
        attributes = sum(_field_bytes(getattr(self, name)) for name in ("tri_n", "tri_uv", "tri_uv1", "tri_tangent",
                                                                        "tri_color") if hasattr(self, name))
        instances = self.instances.device_bytes() if self.has_instances else 0
        others = sum(_field_bytes(f) for f in (self.spheres, self.sphere_frames, self.quads, self.quad_frames,
                                               self.discs_a, self.discs_n, self.prim_material, self.range_end))
        return {"bvh": nodes + slots, "triangles": triangles, "attributes": attributes, "instances": instances,
                "total": nodes + slots + triangles + attributes + instances + others}

    # --- traversal -----------------------------------------------------------------------------
    @ti.func
    def _test_prim(self, g, o, d, k, s, t_max):
        """Test primitive g; returns (hit, t, b1, b2) with primitive-specific surface coordinates.
        (Also the brute-force reference of the tests.)"""
        hit, t, b1, b2 = 0, 0.0, 0.0, 0.0
        if ti.static("triangle" in self.kinds):
            if g < self.range_end[0]:
                v0, v1, v2 = self.corners_of(g)
                if ti.static(self.triangle_test == "watertight"):
                    hit, t, b1, b2 = isect.triangle_watertight(o, k, s, v0, v1, v2, t_max)
                else:
                    hit, t, b1, b2 = isect.triangle_moller_trumbore(o, d, v0, v1, v2, t_max)
        if ti.static("sphere" in self.kinds):
            if g >= self.range_end[0] and g < self.range_end[1]:
                sp = self.spheres[g - self.range_end[0]]
                hit, t = isect.sphere(o, d, sp.xyz, sp.w, t_max)
        if ti.static("quad" in self.kinds):
            if g >= self.range_end[1] and g < self.range_end[2]:
                i = g - self.range_end[1]
                hit, t, b1, b2 = isect.quad_framed(o, d, self.quads[i, 0], self.quad_frames[i, 0],
                                                   self.quad_frames[i, 1], self.quad_frames[i, 2], t_max)
        if ti.static("disc" in self.kinds):
            if g >= self.range_end[2] and g < self.range_end[3]:
                i = g - self.range_end[2]
                hit, t = isect.disc(o, d, self.discs_a[i].xyz, self.discs_n[i], self.discs_a[i].w, t_max)
        if ti.static("bezier" in self.kinds):
            if g >= self.range_end[3]:
                hit, t, b1, b2 = self.bezier.intersect(g - self.range_end[3], o, d, t_max)
        return hit, t, b1, b2

    @ti.func
    def test_leaf(self, first, count, o, d, k, s, hit: ti.template(), any_hit, ray, instance):
        """Test a leaf's primitives (slots first .. first + count - 1) with the ray (o, d) of the
        current frame; `ray` is the world ray and `instance` the instance whose frame o, d are in
        (-1: the world)."""
        if ti.static(self.packed):
            self._test_packets(first, count, o, d, k, s, hit, any_hit, ray, instance)
        else:
            self._test_slots(first, count, o, d, k, s, hit, any_hit, ray, instance)

    @ti.func
    def _test_slots(self, first, count, o, d, k, s, hit: ti.template(), any_hit, ray, instance):
        """The scalar leaf layout: slot after slot."""
        for j in range(first, first + count):
            g = self.slot_prim[j]
            h, t, b1, b2 = self._test_prim(g, o, d, k, s, hit.t)
            hit.tests += 1
            if self._covered(h, g, b1, b2, ray, instance, d) == 1:
                self._take(hit, t, g, b1, b2, instance)
                if any_hit:
                    break

    @ti.func
    def _test_packets(self, first, count, o, d, k, s, hit: ti.template(), any_hit, ray, instance):
        """The packet leaf layout: the packets the leaf's slots touch, four lanes at a time, each
        masked to the leaf's own slots; of a packet's triangle hits the nearest is taken (the
        lowest lane on a tie, as the scalar layout's slot order would), lanes of other kinds after
        it, each only if nearer than the closest hit so far."""
        end = first + count
        ok = permuted_origin(o, k)
        for p in range(first >> 2, ((end - 1) >> 2) + 1):
            mask = self.packets.lane_mask(p, first, end)
            hit.tests += mask.sum()
            prims = self.packets.prims[p]
            if ti.static("triangle" in self.kinds):
                found, t, b1, b2 = ti.math.ivec4(0), ti.math.vec4(0.0), ti.math.vec4(0.0), ti.math.vec4(0.0)
                if ti.static(self.triangle_test == "watertight"):
                    found, t, b1, b2 = self.packets.watertight(p, ok, k, s, hit.t)
                else:
                    found, t, b1, b2 = self.packets.moller_trumbore(p, o, d, hit.t)
                found &= mask
                if ti.static(self.has_alpha):  # lane by lane: the nearest hit may be uncovered
                    for lane in ti.static(range(4)):
                        if found[lane] == 1 and t[lane] < hit.t:
                            if self._covered(1, prims[lane], b1[lane], b2[lane], ray, instance, d) == 1:
                                self._take(hit, t[lane], prims[lane], b1[lane], b2[lane], instance)
                else:
                    t_near, lane, u, v = nearest_lane(found, t, b1, b2)
                    if t_near < hit.t:
                        self._take(hit, t_near, prims[lane], u, v, instance)
            if ti.static(self.has_other_kinds):  # the lanes of other primitives, one by one
                for lane in ti.static(range(4)):
                    g = prims[lane]
                    if mask[lane] == 1 and g >= self.range_end[0]:
                        h, t1, c1, c2 = self._test_prim(g, o, d, k, s, hit.t)
                        if self._covered(h, g, c1, c2, ray, instance, d) == 1:
                            self._take(hit, t1, g, c1, c2, instance)
            if any_hit:
                if hit.hit == 1:
                    break

    @ti.func
    def _covered(self, h, g, b1, b2, ray, instance, d):
        """h (a primitive test's hit flag), cleared where alpha coverage or back-face culling lets
        the ray (direction d in the primitive's frame) pass there; h itself in scenes without
        such materials (no coverage code compiled)."""
        out = h
        if ti.static(self.has_alpha):
            if h == 1:
                out = coverage.covered(self, g, ti.math.vec2(b1, b2), ray.o, ray.d, instance, d)
        return out

    @ti.func
    def _take(self, hit: ti.template(), t, g, b1, b2, instance):
        """Make (t, primitive g, barycentrics) the closest hit so far."""
        hit.hit = 1
        hit.t = t
        hit.prim = g
        hit.bary = ti.math.vec2(b1, b2)
        if ti.static(self.has_instances):
            hit.instance = instance

    @ti.func
    def corners_of(self, g):
        """Triangle g's three corners (in its mesh's frame)."""
        v0, v1, v2 = vec3(0.0), vec3(0.0), vec3(0.0)
        if ti.static(self.packed):
            v0, v1, v2 = self.packets.corners(g)
        else:
            v0, v1, v2 = self.tri_v[g, 0], self.tri_v[g, 1], self.tri_v[g, 2]
        return v0, v1, v2

    @ti.func
    def _ray_setup(self, d):
        """The per-ray constants of the slab and triangle tests."""
        # A zero direction component would give 0 * inf = NaN in the slab test; a tiny stand-in
        # gives the same ordering with finite arithmetic.
        inv_d = 1.0 / ti.select(ti.abs(d) > 1e-30, d, 1e-30)
        k, s = isect.watertight_setup(d)
        return inv_d, k, s

    @ti.func
    def _traverse(self, ray, t_max, any_hit):
        """Closest hit, or (any_hit: a constant or a per-ray value) the first hit found."""
        hit = Hit(hit=0, t=t_max, work=0, tests=0, inside=0, prim=-1, bary=ti.math.vec2(0.0), instance=-1)
        if ti.static(self.traversal in WIDE_TRAVERSALS):
            self.wide.traverse(self, ray, hit, any_hit)
        else:
            self._traverse_binary(ray, hit, any_hit)
        return hit

    @ti.func
    def _traverse_binary(self, ray, hit: ti.template(), any_hit):
        """The "stack" and "stackless" traversals of the binary tree, into `hit`."""
        o = ray.o
        d = ray.d
        inv_d, k, s = self._ray_setup(d)
        instance = -1  # the instance whose frame o, d are in; -1: the world
        if ti.static(self.traversal == "stackless"):
            node = 0
            resume = 0  # the world node after the instance being walked
            while node < self.node_total:
                hit.work += 1
                link = self.node_link[node]
                if isect.box_entry(o, inv_d, self.node_lo[node], self.node_hi[node], hit.t) <= hit.t:
                    if link[1] > 0:
                        self.test_leaf(link[0], link[1], o, d, k, s, hit, any_hit, ray, instance)
                        if any_hit:
                            if hit.hit == 1:
                                break
                        node = link[2]
                    else:
                        node = node + 1
                        if ti.static(self.has_instances):
                            if link[1] == INSTANCE_NODE:  # walk the mesh's tree in the instance's frame
                                instance = link[0]
                                o, d = self.instances.ray_to_object(instance, ray.o, ray.d)
                                inv_d, k, s = self._ray_setup(d)
                                resume = link[2]
                                node = self.instances.root[instance]
                else:
                    node = link[2]
                if ti.static(self.has_instances):
                    if node >= self.node_total and instance >= 0:  # the end of a mesh's tree
                        instance = -1
                        o = ray.o
                        d = ray.d
                        inv_d, k, s = self._ray_setup(d)
                        node = resume
        else:
            stack_node = ti.Vector([0] * self.stack_size, dt=ti.i32)
            stack_t = ti.Vector([0.0] * self.stack_size, dt=ti.f32)
            sp = 0
            node = 0
            if isect.box_entry(o, inv_d, self.node_lo[0], self.node_hi[0], hit.t) > hit.t:
                node = -1
            while node >= 0:
                hit.work += 1
                if ti.static(self.has_instances):
                    if self.node_link[node][1] == INSTANCE_NODE:
                        # Its box was hit: walk its mesh's tree in its frame, from below a marker
                        # that brings the world ray back once that tree is done.
                        instance = self.node_link[node][0]
                        o, d = self.instances.ray_to_object(instance, ray.o, ray.d)
                        inv_d, k, s = self._ray_setup(d)
                        stack_node[sp] = RESUME_WORLD
                        stack_t[sp] = -1.0
                        sp += 1
                        node = self.instances.root[instance]
                        hit.work += 1  # the mesh's root: a visit of its own
                link = self.node_link[node]
                next_node = -1
                if link[1] > 0:
                    self.test_leaf(link[0], link[1], o, d, k, s, hit, any_hit, ray, instance)
                    if any_hit:
                        if hit.hit == 1:
                            break
                else:
                    left = node + 1
                    right = link[0]
                    tl = isect.box_entry(o, inv_d, self.node_lo[left], self.node_hi[left], hit.t)
                    tr = isect.box_entry(o, inv_d, self.node_lo[right], self.node_hi[right], hit.t)
                    if tl <= hit.t and tr <= hit.t:
                        near, far, t_far = left, right, tr
                        if tr < tl:
                            near, far, t_far = right, left, tl
                        stack_node[sp] = far
                        stack_t[sp] = t_far
                        sp += 1
                        next_node = near
                    elif tl <= hit.t:
                        next_node = left
                    elif tr <= hit.t:
                        next_node = right
                # pop, skipping subtrees whose entry lies beyond the closest hit found since the push
                while next_node < 0 and sp > 0:
                    sp -= 1
                    if ti.static(self.has_instances):
                        if stack_node[sp] == RESUME_WORLD:  # (its t of -1 keeps the pop going)
                            instance = -1
                            o = ray.o
                            d = ray.d
                            inv_d, k, s = self._ray_setup(d)
                    if stack_t[sp] <= hit.t:
                        next_node = stack_node[sp]
                node = next_node

    @ti.func
    def intersect(self, ray, t_max):
        return self._traverse(ray, t_max, False)

    @ti.func
    def occluded(self, ray, t_max):
        return self._traverse(ray, t_max, True).hit == 1

    @ti.func
    def trace(self, ray, t_max, any_hit):
        """intersect or, where any_hit (a per-ray value), a shadow ray's search that stops at the
        first hit: one call site of the traversal serves both."""
        return self._traverse(ray, t_max, any_hit)

    # --- shading -------------------------------------------------------------------------------
    @ti.func
    def surface(self, ray, hit):
        g = hit.prim
        p = ray.o + hit.t * ray.d
        n = vec3(0.0, 1.0, 0.0)
        ns = n
        eps = 0.0  # how far a spawned ray must start off the surface (isect.spawn_clearance)
        uv = ti.math.vec2(0.0)
        uv1 = ti.math.vec2(0.0)
        tangent = ti.math.vec4(0.0)
        color = ti.math.vec4(1.0)
        dp_du, dp_dv = vec3(0.0), vec3(0.0)
        footprinted = False  # texture coordinates that vary over the primitive (a footprint to filter)
        if ti.static("triangle" in self.kinds):
            if g < self.range_end[0]:
                bary = hit.bary
                b0 = 1.0 - bary.x - bary.y
                v0, v1, v2 = self.corners_of(g)
                if ti.static(self.has_instances):
                    if hit.instance >= 0:  # the corners in the world, where a world mesh has them
                        v0 = self.instances.point_to_world(hit.instance, v0)
                        v1 = self.instances.point_to_world(hit.instance, v1)
                        v2 = self.instances.point_to_world(hit.instance, v2)
                # From barycentrics, not o + t d: stays on the triangle's plane to f32 precision.
                p = b0 * v0 + bary.x * v1 + bary.y * v2
                eps = isect.spawn_clearance(ti.max(isect.max_abs(v0), ti.max(isect.max_abs(v1), isect.max_abs(v2))))
                n = ti.math.normalize((v1 - v0).cross(v2 - v0))
                if ti.static(self.has_instances):
                    if hit.instance >= 0:
                        if self.instances.mirrored(hit.instance):
                            n = -n  # a mirror turns the winding; the front stays on the same side
                ns = n
                if ti.static(self.has_normals):
                    n0, n1, n2 = self._corner_normals(g, hit.instance)
                    interp = b0 * n0 + bary.x * n1 + bary.y * n2
                    if interp.dot(interp) > 1e-12:  # zero-length normals fall back to the geometric one
                        ns = ti.math.normalize(interp)
                uv, uv1 = self.texture_coordinates(g, bary)
                if ti.static(self.needs_partials):
                    if ti.static(self.has_uvs):
                        dp_du, dp_dv = triangle_uv_partials(v0, v1, v2, self.tri_uv[g, 0], self.tri_uv[g, 1],
                                                            self.tri_uv[g, 2], n)
                        if ti.static(self.filters_textures):
                            # A triangle whose corners share texture coordinates reads one texel.
                            footprinted = uv_area(self.tri_uv[g, 0], self.tri_uv[g, 1], self.tri_uv[g, 2]) != 0.0
                    else:
                        dp_du, dp_dv = barycentric_partials(v0, v1, v2)
                if ti.static(self.has_tangents):
                    t0, t1, t2 = self.tri_tangent[g, 0], self.tri_tangent[g, 1], self.tri_tangent[g, 2]
                    if ti.static(self.has_instances):
                        if hit.instance >= 0:
                            n0, n1, n2 = vec3(0.0), vec3(0.0), vec3(0.0)
                            if ti.static(self.has_normals):
                                n0, n1, n2 = self._corner_normals(g, hit.instance)
                            t0 = self.instances.tangent_to_world(hit.instance, t0, n0)
                            t1 = self.instances.tangent_to_world(hit.instance, t1, n1)
                            t2 = self.instances.tangent_to_world(hit.instance, t2, n2)
                    tg = b0 * t0 + bary.x * t1 + bary.y * t2
                    # Gram-Schmidt against the shading normal; w keeps the handedness sign.
                    txyz = tg.xyz - ns.dot(tg.xyz) * ns
                    if txyz.dot(txyz) > 1e-12:
                        tangent = ti.math.vec4(ti.math.normalize(txyz), 1.0 if tg.w >= 0.0 else -1.0)
                if ti.static(self.has_colors):
                    color = self.corners(self.tri_color, g, bary)
        if ti.static("sphere" in self.kinds):
            if g >= self.range_end[0] and g < self.range_end[1]:
                i = g - self.range_end[0]
                sp = self.spheres[i]
                n = ti.math.normalize(p - sp.xyz)
                p = sp.xyz + sp.w * n  # back onto the sphere
                ns = n
                eps = isect.spawn_clearance(isect.max_abs(sp.xyz) + sp.w)
                uv = isect.sphere_uv(self.sphere_frames[i, 0].dot(n), self.sphere_frames[i, 1].dot(n),
                               self.sphere_frames[i, 2].dot(n))
                footprinted = True
                if ti.static(self.needs_partials):
                    dp_du, dp_dv = sphere_uv_partials(self.sphere_frames[i, 0], self.sphere_frames[i, 1],
                                                      self.sphere_frames[i, 2], sp.w, n)
        if ti.static("quad" in self.kinds):
            if g >= self.range_end[1] and g < self.range_end[2]:
                i = g - self.range_end[1]
                p = self.quads[i, 0] + hit.bary.x * self.quads[i, 1] + hit.bary.y * self.quads[i, 2]
                eps = isect.spawn_clearance(isect.max_abs(self.quads[i, 0]) + isect.max_abs(self.quads[i, 1])
                                            + isect.max_abs(self.quads[i, 2]))
                n = ti.math.normalize(self.quads[i, 1].cross(self.quads[i, 2]))
                ns = n
                uv = hit.bary
                dp_du, dp_dv = self.quads[i, 1], self.quads[i, 2]  # uv runs along the edges
                footprinted = True
        if ti.static(self.has_flipped):
            # Turned over as Mitsuba's flip_normals: the normal only (texture coordinates and dp/du,
            # dp/dv stay), so the front face (emission, one-sided BSDFs) and inside (media) swap.
            if self.is_flipped(g):
                n = -n
                ns = -ns
        if ti.static("disc" in self.kinds):
            if g >= self.range_end[2] and g < self.range_end[3]:
                i = g - self.range_end[2]
                n = self.discs_n[i]
                c = self.discs_a[i].xyz
                p = p - (p - c).dot(n) * n  # back onto the plane
                eps = isect.spawn_clearance(isect.max_abs(c) + self.discs_a[i].w)
                ns = n
                r = (p - c).norm() / self.discs_a[i].w
                uv = ti.math.vec2(r, 0.0)
        if ti.static("bezier" in self.kinds):
            if g >= self.range_end[3]:
                p, n, uv, tangent = self.bezier.surface(g - self.range_end[3], hit.bary.x, hit.bary.y)
                ns = n
        front = 1 if ray.d.dot(n) < 0.0 else 0
        ns = consistent_shading_normal(ns, n, -ray.d)
        cone_width = ray.cone_width + ray.cone_spread * hit.t
        footprint = ti.math.vec4(0.0)
        if ti.static(self.filters_textures):
            if footprinted:
                footprint = uv_footprint(ray.d, n, cone_width, dp_du, dp_dv)
        return Surface(p=p, n_geo=n, n_shading=ns, uv=uv, uv1=uv1, tangent=tangent, material=self.prim_material[g],
                       prim=g, front_face=front, eps=eps, cone_width=cone_width, cone_spread=ray.cone_spread,
                       color=color, dp_du=dp_du, dp_dv=dp_dv, uv_footprint=footprint)

    @ti.func
    def is_flipped(self, g):
        """Whether primitive g is a sphere or quad with its normal turned over (has_flipped only)."""
        flipped = False
        if g >= self.range_end[0] and g < self.range_end[2]:
            flipped = self.flipped[g - self.range_end[0]] != 0
        return flipped

    @ti.func
    def corners(self, f: ti.template(), g, bary):
        """Per-corner attribute f of triangle g at barycentrics bary (of corners 1 and 2)."""
        return (1.0 - bary.x - bary.y) * f[g, 0] + bary.x * f[g, 1] + bary.y * f[g, 2]

    @ti.func
    def texture_coordinates(self, g, bary):
        """Texture coordinate sets 0 and 1 of triangle g at bary (zero where the mesh has none)."""
        uv = ti.math.vec2(0.0)
        uv1 = ti.math.vec2(0.0)
        if ti.static(self.has_uvs):
            uv = self.corners(self.tri_uv, g, bary)
        if ti.static(self.has_uv1):
            uv1 = self.corners(self.tri_uv1, g, bary)
        return uv, uv1

    @ti.func
    def _corner_normals(self, g, instance):
        """Triangle g's vertex normals in the world (instance: its instance, or -1)."""
        n0, n1, n2 = self.tri_n[g, 0], self.tri_n[g, 1], self.tri_n[g, 2]
        if ti.static(self.has_instances):
            if instance >= 0:
                n0 = self.instances.normal_to_world(instance, n0)
                n1 = self.instances.normal_to_world(instance, n1)
                n2 = self.instances.normal_to_world(instance, n2)
        return n0, n1, n2

    @ti.func
    def spawn(self, surface, direction):
        side = surface.n_geo if direction.dot(surface.n_geo) > 0.0 else -surface.n_geo
        return Ray(o=self._leave(surface, side), d=direction,
                   cone_width=surface.cone_width, cone_spread=surface.cone_spread)

    @ti.func
    def _leave(self, surface, side):
        """A ray origin off `surface` on `side`: the surface's clearance `eps` (the rounding of the
        coordinates its point came from, which the point's own magnitude need not show), then a
        few ulps of the point's magnitude (offset_ray_origin)."""
        return isect.offset_ray_origin(surface.p + surface.eps * side, side)

    # --- direct lighting ---------------------------------------------------------------------------
    def primitive_count(self) -> int:
        return self.data.primitive_count

    @staticmethod
    def _material_flags(arrays) -> tuple[bool, bool]:
        """What traversal compiles in for the material rows: coverage tests (alpha: glTF MASK and
        BLEND, Mitsuba's mask; back-face culling), and dp/du, dp/dv on hits (where a material shades
        in their frame, Mitsuba's maps)."""
        if arrays is None:
            return False, False
        alpha = bool(np.any(arrays["alpha_mode"] != ALPHA_OPAQUE) or np.any(arrays["sidedness"] == BACK_CULLED))
        return alpha, bool(needs_uv_partials(arrays))

    def fits_materials(self, arrays) -> bool:
        """Whether edited material rows need nothing traversal was built without (or with)."""
        return self.materials is not None and self._material_flags(arrays) == (self.has_alpha, self.has_uv_partials)

    def objects_of(self, prims: np.ndarray) -> np.ndarray:
        """The scene object (Scene.mesh_objects index) each primitive came from; -1 unknown."""
        return owners_of(prims, self.data.prim_object)

    def emitter_info(self) -> dict:
        """Every primitive with its material, area, bounds and emission cone (for light selection):
        flat shapes emit into the hemisphere of their normal (theta_o 0), spheres all around.
        Bezier patches are left out (their ids come last): an emissive Bezier surface shines where
        paths hit it, but direct lighting does not sample it. So are instanced meshes (below)."""
        d = self.data
        lo, hi = d.bounds()
        n_sampled = d.primitive_count - d.counts["bezier"]
        lo, hi = lo[:n_sampled], hi[:n_sampled]
        tri = d.tri_vertices.astype(np.float64)
        tri_cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        quad_cross = np.cross(d.quads[:, 1], d.quads[:, 2]).astype(np.float64) if len(d.quads) else np.zeros((0, 3))
        cross = np.concatenate([tri_cross, np.zeros((len(d.spheres), 3)), quad_cross, d.discs[:, 3:6]])
        area = np.concatenate([0.5 * np.linalg.norm(tri_cross, axis=1), 4 * np.pi * d.spheres[:, 3] ** 2,
                               np.linalg.norm(quad_cross, axis=1), np.pi * d.discs[:, 6] ** 2])
        length = np.linalg.norm(cross, axis=1, keepdims=True)
        axis = np.where(length > 0, cross / np.maximum(length, 1e-30), [0.0, 1.0, 0.0])
        if len(d.quads):  # a quad turned over emits against edge u x edge v
            quads = slice(d.counts["triangle"] + d.counts["sphere"], d.counts["triangle"] + d.counts["sphere"]
                          + d.counts["quad"])
            axis[quads] *= np.where(d.analytic_flipped()[d.counts["sphere"]:, None] != 0, -1.0, 1.0)
        theta_o = np.zeros(len(area))
        theta_o[d.counts["triangle"]:d.counts["triangle"] + d.counts["sphere"]] = np.pi
        # Instanced meshes are not sampled: they are stored in their own frames, and assembly
        # places emissive meshes in the world instead.
        sampled = d.world_prims()
        sampled = sampled[sampled < n_sampled]
        return {"prim": sampled.astype(np.int32), "material": d.materials()[sampled], "area": area[sampled],
                "lo": lo[sampled], "hi": hi[sampled], "axis": axis[sampled], "theta_o": theta_o[sampled],
                "theta_e": np.full(len(sampled), np.pi / 2)}

    @ti.func
    def material_of(self, g):
        return self.prim_material[g]

    @ti.func
    def sample_emitter(self, g, ref, u):
        result = EmitterPoint(p=ref, n=vec3(0.0, 1.0, 0.0), uv=ti.math.vec2(0.0), pdf=0.0)
        if ti.static("triangle" in self.kinds):
            if g < self.range_end[0]:
                v0, v1, v2 = self.corners_of(g)
                result = shapes.triangle_sample(v0, v1, v2, ref, u)
                if ti.static(self.has_uvs):
                    result.uv = self.corners(self.tri_uv, g, result.uv)  # uv held the barycentrics
        if ti.static("sphere" in self.kinds):
            if g >= self.range_end[0] and g < self.range_end[1]:
                sp = self.spheres[g - self.range_end[0]]
                result = shapes.sphere_sample(sp.xyz, sp.w, ref, u)
        if ti.static("quad" in self.kinds):
            if g >= self.range_end[1] and g < self.range_end[2]:
                i = g - self.range_end[1]
                result = shapes.quad_sample(self.quads[i, 0], self.quads[i, 1], self.quads[i, 2], ref, u)
        if ti.static("disc" in self.kinds):
            if g >= self.range_end[2] and g < self.range_end[3]:
                i = g - self.range_end[2]
                result = shapes.disc_sample(self.discs_a[i].xyz, self.discs_n[i], self.discs_a[i].w, ref, u)
        if ti.static(self.has_flipped):
            # The sampled point's normal as its hits have it: the emitting side is where it points
            # (a sphere turned over emits inwards; its densities do not depend on the normal's sign).
            if self.is_flipped(g):
                result.n = -result.n
        return result

    @ti.func
    def emitter_pdf(self, g, ref, p, n):
        pdf = 0.0
        if ti.static("triangle" in self.kinds):
            if g < self.range_end[0]:
                v0, v1, v2 = self.corners_of(g)
                pdf = shapes.triangle_pdf(v0, v1, v2, ref, p, n)
        if ti.static("sphere" in self.kinds):
            if g >= self.range_end[0] and g < self.range_end[1]:
                sp = self.spheres[g - self.range_end[0]]
                pdf = shapes.sphere_pdf(sp.xyz, sp.w, ref, p, n)
        if ti.static("quad" in self.kinds):
            if g >= self.range_end[1] and g < self.range_end[2]:
                i = g - self.range_end[1]
                pdf = shapes.quad_pdf(self.quads[i, 1], self.quads[i, 2], ref, p, n)
        if ti.static("disc" in self.kinds):
            if g >= self.range_end[2] and g < self.range_end[3]:
                i = g - self.range_end[2]
                pdf = shapes.disc_pdf(self.discs_n[i], self.discs_a[i].w, ref, p, n)
        return pdf

    @ti.func
    def next_segment(self, surface, direction, target, target_n, to_target):
        """The next ray leaving `surface` and how far to trace it: along `direction` without a
        limit, or (to_target) a shadow ray to `target` with both ends offset off their surfaces
        (pbrt's SpawnRayTo), stopping short of the target's own surface; 0 when there is nothing
        to trace. Integrators trace both kinds at one call site of the traversal."""
        ray = Ray(o=surface.p, d=direction, cone_width=surface.cone_width, cone_spread=surface.cone_spread)
        if surface.eps >= 0.0:  # on a surface (not a MEDIUM_POINT): leave it
            ray = self.spawn(surface, direction)
        t_max = INF
        if to_target:
            to = target - surface.p
            side = surface.n_geo if to.dot(surface.n_geo) > 0.0 else -surface.n_geo
            o = surface.p
            if surface.eps >= 0.0:
                o = self._leave(surface, side)
            far_side = target_n if (o - target).dot(target_n) > 0.0 else -target_n
            seg = isect.offset_ray_origin(target, far_side) - o
            length = seg.norm()
            t_max = 0.0
            if length > 0.0:
                ray = Ray(o=o, d=seg / length, cone_width=0.0, cone_spread=0.0)
                # 1 - 1e-4: the offset end point is already off the target's surface; this margin
                # only absorbs the rounding of `length`.
                t_max = length * (1.0 - 1e-4)
        return ray, t_max

    @ti.func
    def visible(self, surface, target, target_n):
        """Nothing blocks the shadow ray of next_segment (any hit ends the search)."""
        ray, t_max = self.next_segment(surface, target - surface.p, target, target_n, True)
        blocked = False
        if t_max > 0.0:
            blocked = self.occluded(ray, t_max)
        return not blocked



def _field_bytes(f) -> int:
    """Bytes of a field of 4-byte scalars or vectors."""
    return int(np.prod(f.shape)) * getattr(f, "n", 1) * 4

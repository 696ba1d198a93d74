"""The 4-wide BVH: its collapse of the binary tree (every primitive referenced once, every child box
holding its subtree, empty slots that no ray enters) and its traversal (closest hit and any hit
equal brute force and the binary traversal, instancing included, degenerate and extreme inputs),
and a mesh scene rendered with it equals the binary traversal's image bit for bit."""
import numpy as np
import pytest
import taichi as ti

from renderer.bench.ray_batch import ray_at
from renderer.camera import CameraFrame
from renderer.geometry.bvh_build import build_bvh
from renderer.geometry.instance_bvh import INSTANCE_NODE, build_scene_bvh
from renderer.geometry.interface import INF
from renderer.geometry.intersect import watertight_setup
from renderer.geometry.mesh_data import MeshData
from renderer.geometry.wide_bvh import EMPTY_CHILD, F32_MAX, WIDTH, collapse
from renderer.geometry.wide_traversal import stack_size
from renderer.renderer import MeshOptions, Renderer
from renderer.scene.catalog import load_any
from tests.geometry.hit_bounds import triangle_shape, triangle_tolerance
from tests.geometry.mesh_helpers import RayShooter, geometry_from
from tests.geometry.test_instancing import HitProbe, paired_scenes, point_bound
from tests.geometry.test_instancing import random_rays as instancing_rays
from tests.geometry.test_traversal import mixed_scene, random_rays
from tests.stats.image_tests import assert_agree


# ------------------------------------------------------------------------------------------------
# the collapse (numpy)


def triangles(rng, n, spread=2.0, size=0.25):
    centres = rng.uniform(-spread, spread, (n, 1, 3))
    return (centres + rng.normal(0, size, (n, 3, 3))).astype(np.float32)


def data_of(tris) -> MeshData:
    return MeshData(tri_vertices=np.ascontiguousarray(tris, np.float32), tri_material=np.zeros(len(tris), np.int32))


def degenerate_inputs():
    rng = np.random.default_rng(11)
    point = np.full((300, 3, 3), 0.5, np.float32)
    return {
        "one": triangles(rng, 1),
        "two": triangles(rng, 2),
        "five": triangles(rng, 5),
        "at_one_point": point,
        "huge": triangles(rng, 400, spread=2e6, size=3e5),
        "tiny": triangles(rng, 400, spread=2e-5, size=3e-6),
        "far_from_origin": triangles(rng, 400) + np.float32(1e4),
        "random": triangles(rng, 3000),
    }


INPUTS = degenerate_inputs()


def wide_of(tris, leaf=4, strategy="sah", width=WIDTH):
    data = data_of(tris)
    lo, hi = data.bounds()
    binary = build_bvh(lo, hi, 0.5 * (lo + hi), strategy=strategy, max_leaf_size=leaf)
    return binary, collapse(binary, width=width), lo, hi


def reachable(wide, root=0):
    """Wide nodes below `root` in visiting order (each listed as often as it is reached)."""
    order, frontier = [], [root]
    while frontier:
        order += frontier
        rows = np.asarray(frontier)
        inner = wide.child_count[rows] == 0
        frontier = list(wide.child_a[rows][inner])
    return np.asarray(order)


@pytest.mark.parametrize("name", INPUTS)
@pytest.mark.parametrize("leaf", [1, 4])
@pytest.mark.parametrize("width", [4, 8])
def test_every_primitive_is_referenced_once_and_every_node_once(name, leaf, width):
    binary, wide, _, _ = wide_of(INPUTS[name], leaf, width=width)
    assert wide.width == width
    nodes = reachable(wide)
    assert np.array_equal(np.sort(nodes), np.arange(wide.num_nodes)), "each wide node reached exactly once"
    leaves = wide.child_count[nodes] > 0
    first, count = wide.child_a[nodes][leaves], wide.child_count[nodes][leaves]
    slots = np.concatenate([np.arange(f, f + c) for f, c in zip(first, count)])
    assert np.array_equal(np.sort(slots), np.arange(len(INPUTS[name]))), "each slot in exactly one leaf"
    assert np.array_equal(np.sort(wide.prim_order), np.arange(len(INPUTS[name])))
    # the same leaves as the binary tree, so no leaf grew
    assert sorted(zip(first, count)) == sorted(zip(binary.node_a[binary.node_count > 0],
                                                   binary.node_count[binary.node_count > 0]))


@pytest.mark.parametrize("name", INPUTS)
@pytest.mark.parametrize("width", [4, 8])
def test_child_boxes_hold_their_subtrees_and_empty_slots_are_inverted(name, width):
    _, wide, lo, hi = wide_of(INPUTS[name], width=width)
    box_lo, box_hi = wide.bounds[:, 0:3], wide.bounds[:, 3:6]  # (M, 3, width)
    count, a = wide.child_count, wide.child_a
    lo32, hi32 = lo.astype(np.float32), hi.astype(np.float32)  # MeshData bounds are f32 already
    for node in range(wide.num_nodes):
        for c in range(width):
            if count[node, c] == EMPTY_CHILD:
                assert (box_lo[node, :, c] == F32_MAX).all() and (box_hi[node, :, c] == -F32_MAX).all()
            elif count[node, c] == 0:  # an inner child: holds every box of its node's children
                below = a[node, c]
                used = count[below] != EMPTY_CHILD
                assert used.sum() >= 2, "an inner wide node has at least two children"
                assert (box_lo[below][:, used] >= box_lo[node, :, c:c + 1]).all()
                assert (box_hi[below][:, used] <= box_hi[node, :, c:c + 1]).all()
            else:  # a leaf: holds its primitives' boxes
                prims = wide.prim_order[a[node, c]:a[node, c] + count[node, c]]
                assert (lo32[prims] >= box_lo[node, :, c]).all() and (hi32[prims] <= box_hi[node, :, c]).all()
    # empty slots only where a node has fewer children than slots: every node opens what it can
    inner_slots = (count == 0).sum(axis=1)
    empties = (count == EMPTY_CHILD).sum(axis=1)
    assert ((empties == 0) | (inner_slots == 0)).all()


@pytest.mark.parametrize("width", [4, 8])
def test_roots_and_depths_of_several_trees(width):
    rng = np.random.default_rng(12)
    instanced, _, _, _ = paired_scenes(rng)
    scene = build_scene_bvh(instanced)
    roots = np.concatenate([[0], scene.mesh_root])
    wide = collapse(scene.nodes, roots, width)
    assert list(wide.roots) == list(range(len(roots)))
    seen = np.concatenate([reachable(wide, r) for r in wide.roots])
    assert np.array_equal(np.sort(seen), np.arange(wide.num_nodes)), "the trees share no node"
    # every instance child of the world is one instance, once
    instances = wide.child_a[wide.child_count == INSTANCE_NODE]
    assert sorted(instances) == list(range(len(instanced.instance_mesh)))
    for r in wide.roots:
        levels, frontier = 0, [r]
        while frontier:
            levels += 1
            rows = np.asarray(frontier)
            frontier = list(wide.child_a[rows][wide.child_count[rows] == 0])
        assert wide.depth[r] == levels
    assert stack_size(wide) == (width - 1) * (wide.depth[0] + wide.depth[1:].max()) + 1


@pytest.mark.parametrize("name", ["one", "random", "at_one_point"])
def test_packed_references_decode_to_the_children(name):
    _, wide, _, _ = wide_of(INPUTS[name])
    refs, bits = wide.packed_refs()
    count, a = wide.child_count, wide.child_a
    inner = count == 0
    assert np.array_equal(refs[inner], a[inner]) and (refs[~inner] < 0).all()
    leaf = count > 0
    packed = ~refs[leaf].astype(np.int64)
    assert np.array_equal(packed >> bits, a[leaf]) and np.array_equal(packed & ((1 << bits) - 1), count[leaf])
    assert count.max() < 2 ** bits


def test_collapse_refuses_roots_outside_the_tree():
    binary, _, _, _ = wide_of(INPUTS["five"])
    with pytest.raises(ValueError, match="roots"):
        collapse(binary, [binary.num_nodes])
    with pytest.raises(ValueError, match="root"):
        collapse(binary, [])
    with pytest.raises(ValueError, match="width 6"):
        collapse(binary, width=6)


def test_eight_wide_nodes_are_fuller_and_fewer():
    binary, wide4, _, _ = wide_of(INPUTS["random"])
    _, wide8, _, _ = wide_of(INPUTS["random"], width=8)
    assert wide8.num_nodes < wide4.num_nodes and wide8.depth[0] < wide4.depth[0]
    used4, used8 = ((w.child_count != EMPTY_CHILD).sum(axis=1).mean() for w in (wide4, wide8))
    assert used8 > used4 > 3.0


# ------------------------------------------------------------------------------------------------
# traversal on the device


@ti.data_oriented
class HitRecorder:
    """Closest hits with their barycentrics, by a geometry's traversal or by testing every
    primitive: columns t, b1, b2 (f32) and prim (i32; -1: a miss)."""

    def __init__(self, geometry):
        self.geometry = geometry

    @ti.kernel
    def _trace(self, o: ti.types.ndarray(), d: ti.types.ndarray(), brute: ti.i32, out: ti.types.ndarray(),
               prim: ti.types.ndarray()):
        for i in range(o.shape[0]):
            ray = ray_at(o, d, i)
            t, b1, b2, g = INF, 0.0, 0.0, -1
            if brute:
                k, s = watertight_setup(ray.d)
                for p in range(self.geometry.prim_material.shape[0]):
                    h, th, c1, c2 = self.geometry._test_prim(p, ray.o, ray.d, k, s, t)
                    if h == 1:
                        t, b1, b2, g = th, c1, c2, p
            else:
                hit = self.geometry.intersect(ray, INF)
                if hit.hit == 1:
                    t, b1, b2, g = hit.t, hit.bary.x, hit.bary.y, hit.prim
            out[i, 0] = t
            out[i, 1] = b1
            out[i, 2] = b2
            prim[i] = g

    def trace(self, o, d, brute=False):
        out = np.zeros((len(o), 3), np.float32)
        prim = np.zeros(len(o), np.int32)
        self._trace(np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32), int(brute), out, prim)
        return out, prim


def assert_same_hits(got, ref, data: MeshData, d, min_hits):
    """Both hit or both miss, and hits of the same primitive agree to rounding: the same f32 test,
    compiled into another kernel, where fast math may associate its sums differently. On a
    triangle each result lies within hit_bounds' bound of the exact hit (t within
    triangle_tolerance, barycentrics within that over the smallest altitude, >= L / kappa), so
    two lie within twice that; other shapes (mixed_scene's, of unit size) within 1e-5 (t + 1).
    A different primitive is right only at the same distance (two primitives meet there: a tie)."""
    (a, pa), (b, pb) = got, ref
    assert (pb >= 0).sum() >= min_hits, "the rays must actually hit things"
    np.testing.assert_array_equal(pa >= 0, pb >= 0)
    same = (pa == pb) & (pb >= 0)
    t = b[:, 0].astype(np.float64)
    tol_t = 1e-5 * (t + 1.0)
    tol_bary = np.full(len(t), 1e-5)
    on_triangle = same & (pb < len(data.tri_vertices))
    longest, kappa, normal = triangle_shape(data.tri_vertices[pb[on_triangle]])
    cosine = np.abs((d[on_triangle] * normal).sum(axis=1))
    tol_t[on_triangle] = 2.0 * triangle_tolerance(t[on_triangle], longest, kappa, cosine)
    tol_bary[on_triangle] = tol_t[on_triangle] * kappa / longest
    assert (np.abs(a[same, 0] - t[same]) <= tol_t[same]).all()
    assert (np.abs(a[same, 1:] - b[same, 1:]).max(axis=1) <= tol_bary[same]).all()
    tie = (pa != pb)
    assert np.allclose(a[tie, 0], b[tie, 0], rtol=1e-5, atol=0), f"{tie.sum()} rays hit other primitives"
    assert tie.mean() < 1e-3


def axis_rays(rng, n, lo, hi):
    """Rays from points around the box [lo, hi] along the axes, and diagonally within the
    coordinate planes: zero direction components, both ways."""
    margin = 0.5 * (hi - lo).max()
    o = rng.uniform(lo - margin, hi + margin, (n, 3))
    d = np.zeros((n, 3))
    rows = np.arange(n)
    axis = rng.integers(0, 3, n)
    d[rows, axis] = rng.choice([-1.0, 1.0], n)
    plane = rows[: n // 2]
    d[plane, (axis[plane] + 1) % 3] = rng.choice([-1.0, 1.0], len(plane))
    return o, d / np.linalg.norm(d, axis=1, keepdims=True)


@pytest.fixture(scope="module")
def mixed():
    rng = np.random.default_rng(1)
    return mixed_scene(rng), random_rays(rng, 20000)


@pytest.mark.parametrize("strategy, traversal", [("sah", "wide4"), ("midpoint", "wide4"), ("sah", "wide8")])
def test_closest_hit_equals_brute_force_and_the_binary_traversal(mixed, strategy, traversal):
    """Triangles, spheres, quads and discs in one tree: t, primitive and barycentrics of the wide
    traversal equal brute force's and the stack traversal's."""
    data, (o, d) = mixed
    wide = HitRecorder(geometry_from(data, strategy=strategy, traversal=traversal))
    got = wide.trace(o, d)
    assert_same_hits(got, wide.trace(o, d, brute=True), data, d, 10000)
    stack = HitRecorder(geometry_from(data, strategy=strategy, traversal="stack"))
    assert_same_hits(got, stack.trace(o, d), data, d, 10000)


@pytest.mark.parametrize("traversal", ["wide4", "wide8"])
def test_any_hit_equals_brute_force(mixed, traversal):
    data, (o, d) = mixed
    shooter = RayShooter(geometry_from(data, traversal=traversal))
    t_ref, _ = shooter.closest(o, d, brute=True)
    for t_max in (0.5, 1.5, 4.0, INF):
        blocked = shooter.occluded(o, d, t_max) == 1
        assert np.array_equal(blocked, t_ref < t_max)
        assert 0 < blocked.sum() < len(o) or t_max == INF


def test_trace_stops_shadow_rays_at_the_first_hit(mixed):
    """A per-ray any-hit flag (the path tracer's one call site): flagged rays report the same
    occlusion with fewer primitive tests; unflagged rays are the closest-hit search."""
    data, (o, d) = mixed
    shooter = RayShooter(geometry_from(data, traversal="wide4"))
    n = len(o)
    hit_any, tests_any = shooter.trace(o, d, 3.0, np.ones(n))
    hit_closest, tests_closest = shooter.trace(o, d, 3.0, np.zeros(n))
    assert np.array_equal(hit_any, hit_closest)
    assert (tests_any <= tests_closest).all() and tests_any.sum() < 0.9 * tests_closest.sum()
    mixed_flags = (np.arange(n) % 2).astype(np.int32)
    hit_mixed, tests_mixed = shooter.trace(o, d, 3.0, mixed_flags)
    assert np.array_equal(hit_mixed, hit_closest)
    assert np.array_equal(tests_mixed, np.where(mixed_flags == 1, tests_any, tests_closest))


@pytest.mark.parametrize("name", INPUTS)
def test_degenerate_and_extreme_inputs_trace_as_brute_force(name):
    """Rays aimed at points on the triangles from all around, and rays along the axes and the
    coordinate planes (zero direction components meet the empty slots' and the boxes' planes
    edge-on), through every input."""
    tris = INPUTS[name].astype(np.float64)
    rng = np.random.default_rng(13)
    lo, hi = tris.reshape(-1, 3).min(axis=0), tris.reshape(-1, 3).max(axis=0)
    centre = 0.5 * (lo + hi)
    size = max((hi - lo).max(), 1e-3 * max(np.abs(lo).max(), 1e-30))
    n = 6000
    weights = rng.dirichlet(np.ones(3), n)
    targets = np.einsum("nk,nkj->nj", weights, tris[rng.integers(0, len(tris), n)])
    origins = centre + size * 2.0 * rng.normal(size=(n, 3))
    d = targets - origins
    ao, ad = axis_rays(rng, 4000, lo, hi + size * 1e-3)
    o = np.concatenate([origins, ao])
    d = np.concatenate([d / np.linalg.norm(d, axis=1, keepdims=True), ad])
    recorder = HitRecorder(geometry_from(data_of(INPUTS[name]), traversal="wide4"))
    got, ref = recorder.trace(o, d), recorder.trace(o, d, brute=True)
    assert_same_hits(got, ref, data_of(INPUTS[name]), d, 0 if name == "at_one_point" else n // 2)
    if name == "at_one_point":
        assert (got[1] < 0).all(), "triangles of zero area are never hit"


@pytest.fixture(scope="module")
def paired():
    rng = np.random.default_rng(7)
    instanced, flat, tw, tm = paired_scenes(rng)
    return instanced, flat, tw, tm, instancing_rays(rng, 20000)


def same_instanced_hits(got, ref):
    """HitProbe rows of two traversals of one two-level scene: both hit or both miss, many hits
    are in instances, and at least 99.9 % of hits find the same primitive and instance (the rest:
    ties where two meet). Returns the mask of those."""
    np.testing.assert_array_equal(got[:, HitProbe.HIT], ref[:, HitProbe.HIT])
    hit = ref[:, HitProbe.HIT] == 1
    assert hit.sum() > 3000 and (ref[hit, HitProbe.INSTANCE] >= 0).sum() > 2000
    columns = [HitProbe.PRIM, HitProbe.INSTANCE]
    same = hit & (got[:, columns] == ref[:, columns]).all(axis=1)
    assert same.sum() > 0.999 * hit.sum()
    return same


@pytest.mark.parametrize("loose, traversal", [(40, "wide4"), (0, "wide4"), (40, "wide8")])
def test_instanced_scene_traces_as_the_binary_traversal(loose, traversal):
    """Two-level scenes (with world triangles, and instances alone): the wide traversal finds the
    stack traversal's primitive and instance, and t and barycentrics within rounding (each
    within test_instancing's point_bound of the exact hit, so within twice it of each other)."""
    rng = np.random.default_rng(7 + loose)
    instanced, flat, tw, tm = paired_scenes(rng, loose=loose)
    o, d = instancing_rays(rng, 20000)
    got = HitProbe(geometry_from(instanced, traversal=traversal)).shoot(o, d)
    ref = HitProbe(geometry_from(instanced, traversal="stack")).shoot(o, d)
    same = same_instanced_hits(got, ref)
    prim, instance = ref[same, HitProbe.PRIM].astype(int), ref[same, HitProbe.INSTANCE].astype(int)
    world = np.where(instance >= 0, tw + instance * tm + (prim - tw), prim)
    t = ref[same, HitProbe.T].astype(np.float64)
    bound = 2.0 * point_bound(o[same], d[same], t, flat.tri_vertices[world], instance, instanced,
                              instanced.tri_vertices[prim])
    assert (np.abs(got[same, HitProbe.T] - t) <= bound).all()
    longest, kappa, _ = triangle_shape(flat.tri_vertices[world])
    bary = np.abs(got[same][:, HitProbe.BARY] - ref[same][:, HitProbe.BARY]).max(axis=1)
    assert (bary <= bound * kappa / longest).all()


def test_instanced_any_hit_equals_flattened(paired):
    instanced, flat, _, _, (o, d) = paired
    t_ref, _ = RayShooter(geometry_from(flat)).closest(o, d, brute=True)
    shooter = RayShooter(geometry_from(instanced, traversal="wide4"))
    for t_max in (2.0, 8.0, INF):
        blocked = shooter.occluded(o, d, t_max) == 1
        clear = np.abs(t_ref - t_max) > 1e-4 * np.maximum(1.0, t_ref)  # not at the very end of the segment
        assert np.array_equal(blocked[clear], (t_ref < t_max)[clear])
        assert blocked.sum() > 1000


@pytest.mark.parametrize("width", [4, 8])
def test_device_bytes_count_the_wide_nodes(mixed, width):
    data, _ = mixed
    binary = build_scene_bvh(data)
    geometry = geometry_from(data, traversal=f"wide{width}")
    wide = collapse(binary, width=width)
    assert geometry.device_bytes()["bvh"] == wide.num_nodes * (6 * width * 4 + width * 4) + binary.num_prims * 4
    assert wide.num_nodes < binary.num_nodes / 2


# ------------------------------------------------------------------------------------------------
# a whole render


def render(path, traversal, seed, spp=4, size=(40, 30), leaves="scalar"):
    scene = load_any(path)
    r = Renderer(scene, size, mesh_options=MeshOptions(traversal=traversal, leaves=leaves))
    r.render(CameraFrame.from_spec(scene.camera), spp, integrator="mis", seed=seed)
    return r.image(), r.film.variance_of_mean_image()


# Whole renders, one scene each way (the ray-level tests above hold every hit of random, degenerate,
# instanced and cut-out inputs to brute force): the Cornell box (quads and triangles) bit for bit,
# and the textured scene (textures read at the hits' barycentrics, an environment map) by z-test.
@pytest.mark.parametrize("path", ["assets/scenes/cornell_box.toml"])
def test_mesh_scene_renders_bit_identical_to_the_binary_traversal(path):
    """The same hits give the same image, bit for bit, at the same seed."""
    stack, _ = render(path, "stack", 3)
    wide, _ = render(path, "wide4", 3)
    assert stack.mean() > 0.01
    np.testing.assert_array_equal(stack, wide)


@pytest.mark.filterwarnings("ignore::renderer.output.image_io.NegativePixelsWarning")
@pytest.mark.parametrize("path", ["assets/scenes/textured.toml"])
def test_mesh_scene_renders_z_equal_to_the_binary_traversal(path):
    """A scene whose hits the two traversals round differently in the last bits (the triangle test
    compiled into another kernel: fast math may associate its sums otherwise): independent renders (different seeds) agree by the suite's per-pixel
    and image-mean z-tests."""
    stack = render(path, "stack", 5, spp=16)
    wide = render(path, "wide4", 6, spp=16)
    assert stack[0].mean() > 0.01
    assert_agree(wide, stack, ("wide4", "stack"))

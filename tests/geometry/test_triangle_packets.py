"""Leaves of four-slot packets (renderer/geometry/triangle_packets.py): the layout (numpy), and
traversal with packet leaves against brute force and the scalar leaves, for the wide and the
binary trees, both triangle tests, other primitive kinds in the lanes, degenerate input,
instances and alpha coverage; and whole renders against the scalar layout."""
import numpy as np
import pytest
import taichi as ti

from renderer.bench.ray_batch import ray_at
from renderer.geometry.instance_bvh import build_scene_bvh
from renderer.geometry.interface import INF, Hit
from renderer.geometry.mesh_data import MeshData
from renderer.geometry.triangle_packets import LANES, NO_PRIM, ROWS, TrianglePackets, build_packets
from renderer.geometry.wide_bvh import collapse
from renderer.geometry.wide_traversal import WideNodes
from tests.geometry.mesh_helpers import RayShooter, geometry_from
from tests.geometry.test_alpha_coverage import blend_row
from tests.geometry.test_instancing import HitProbe, paired_scenes
from tests.geometry.test_instancing import random_rays as instancing_rays
from tests.geometry.test_traversal import mixed_scene, random_rays
from tests.geometry.test_wide_bvh import (INPUTS, HitRecorder, assert_same_hits, axis_rays, data_of, render,
                                          same_instanced_hits)
from tests.stats.image_tests import assert_agree

# ------------------------------------------------------------------------------------------------
# the layout (numpy)


def test_every_slot_sits_in_its_packet_lane_with_its_corners():
    rng = np.random.default_rng(3)
    tris = rng.normal(size=(23, 3, 3)).astype(np.float32)
    order = rng.permutation(30)  # ids 23..29: other primitive kinds
    packets = build_packets(order, tris)
    assert packets.num_packets == 8 and packets.rows.shape == (8, ROWS, LANES)
    flat = packets.prims.ravel()
    np.testing.assert_array_equal(flat[:30], order)
    assert (flat[30:] == NO_PRIM).all()
    corners = packets.rows.transpose(0, 2, 1).reshape(-1, 3, 3)  # per slot: corner, axis
    for slot, g in enumerate(flat):
        expected = tris[g] if 0 <= g < 23 else np.zeros((3, 3), np.float32)
        np.testing.assert_array_equal(corners[slot], expected)
    np.testing.assert_array_equal(flat[packets.tri_slot], np.arange(23))


def test_a_primitive_order_without_some_triangle_is_refused():
    tris = np.zeros((5, 3, 3), np.float32)
    with pytest.raises(ValueError, match="leaves out triangles"):
        build_packets(np.array([0, 1, 2, 4]), tris)


def test_device_bytes_count_the_packets_and_stay_under_64_a_triangle():
    """Dense packets: 40 bytes a slot (the last packet padded), 4 more a triangle for its slot;
    with the wide nodes, at most 64 bytes a triangle on a mesh of random triangles."""
    data = data_of(INPUTS["random"])
    geometry = geometry_from(data, traversal="wide4", leaves="packets")
    packets = -(-len(data.tri_vertices) // LANES)
    wide = collapse(build_scene_bvh(data))
    sizes = geometry.device_bytes()
    assert sizes["triangles"] == packets * ROWS * LANES * 4 + len(data.tri_vertices) * 4
    assert sizes["bvh"] == wide.num_nodes * WideNodes.bytes_per_node(4) + packets * LANES * 4
    assert TrianglePackets.BYTES_PER_PACKET == 160
    assert (sizes["bvh"] + sizes["triangles"]) / len(data.tri_vertices) <= 64.0


def test_an_unknown_leaf_layout_is_refused():
    with pytest.raises(ValueError, match="unknown leaf layout 'simd'"):
        geometry_from(data_of(INPUTS["two"]), leaves="simd")


# ------------------------------------------------------------------------------------------------
# traversal on the device


@ti.data_oriented
class AllSlots(HitRecorder):
    """Brute force through the packet leaves' own code: every slot as one leaf (the same 4-lane
    test the traversal runs, so hit and miss decisions must agree exactly)."""

    @ti.kernel
    def _all_slots(self, o: ti.types.ndarray(), d: ti.types.ndarray(), slots: ti.i32, out: ti.types.ndarray(),
                   prim: ti.types.ndarray()):
        for i in range(o.shape[0]):
            ray = ray_at(o, d, i)
            _, k, s = self.geometry._ray_setup(ray.d)
            hit = Hit(hit=0, t=INF, work=0, tests=0, inside=0, prim=-1, bary=ti.math.vec2(0.0), instance=-1)
            self.geometry.test_leaf(0, slots, ray.o, ray.d, k, s, hit, False, ray, -1)
            out[i, 0] = hit.t
            out[i, 1] = hit.bary.x
            out[i, 2] = hit.bary.y
            prim[i] = hit.prim if hit.hit == 1 else -1

    def all_slots(self, o, d):
        out = np.zeros((len(o), 3), np.float32)
        prim = np.zeros(len(o), np.int32)
        self._all_slots(np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32),
                        len(self.geometry.data.materials()), out, prim)
        return out, prim


@pytest.fixture(scope="module")
def mixed():
    rng = np.random.default_rng(1)
    return mixed_scene(rng), random_rays(rng, 20000)


@pytest.mark.parametrize("traversal, triangle_test", [("wide4", "watertight"), ("wide4", "moller"),
                                                      ("wide8", "watertight"), ("wide8", "moller"), ("stack", "watertight"),
                                                      ("stackless", "moller")])
def test_closest_hit_equals_brute_force_and_the_scalar_leaves(mixed, traversal, triangle_test):
    """Triangles, spheres, quads and discs in one tree (other kinds share packets with
    triangles): t, primitive and barycentrics equal brute force's and the scalar layout's."""
    data, (o, d) = mixed
    packed = HitRecorder(geometry_from(data, traversal=traversal, triangle_test=triangle_test, leaves="packets"))
    got = packed.trace(o, d)
    assert_same_hits(got, packed.trace(o, d, brute=True), data, d, 10000)
    scalar = HitRecorder(geometry_from(data, traversal=traversal, triangle_test=triangle_test))
    assert_same_hits(got, scalar.trace(o, d), data, d, 10000)


def test_any_hit_equals_brute_force_and_stops_early(mixed):
    data, (o, d) = mixed
    shooter = RayShooter(geometry_from(data, traversal="wide4", leaves="packets"))
    t_ref, _ = shooter.closest(o, d, brute=True)
    for t_max in (0.5, 1.5, 4.0):
        blocked = shooter.occluded(o, d, t_max) == 1
        assert np.array_equal(blocked, t_ref < t_max)
        assert 0 < blocked.sum() < len(o)
    n = len(o)
    hit_any, tests_any = shooter.trace(o, d, 3.0, np.ones(n))
    hit_closest, tests_closest = shooter.trace(o, d, 3.0, np.zeros(n))
    assert np.array_equal(hit_any, hit_closest)
    assert (tests_any <= tests_closest).all() and tests_any.sum() < 0.9 * tests_closest.sum()


@pytest.mark.parametrize("name", ["one", "five", "at_one_point", "huge", "tiny", "far_from_origin"])
def test_degenerate_and_extreme_inputs_trace_as_brute_force(name):
    """Rays at points on the triangles from all around and along the axes (zero direction
    components: the permuted origin and shear of the watertight test), through every input: the
    traversal finds what testing every slot with the packet test finds; and that agrees with the
    scalar test but for rays that the two roundings put on either side of an edge (far from the
    origin, a triangle 0.25 across at 1e4 spans only ~250 float32 steps)."""
    tris = INPUTS[name].astype(np.float64)
    rng = np.random.default_rng(17)
    lo, hi = tris.reshape(-1, 3).min(axis=0), tris.reshape(-1, 3).max(axis=0)
    size = max((hi - lo).max(), 1e-3 * max(np.abs(lo).max(), 1e-30))
    n = 4000
    weights = rng.dirichlet(np.ones(3), n)
    targets = np.einsum("nk,nkj->nj", weights, tris[rng.integers(0, len(tris), n)])
    origins = 0.5 * (lo + hi) + size * 2.0 * rng.normal(size=(n, 3))
    d = targets - origins
    ao, ad = axis_rays(rng, 3000, lo, hi + size * 1e-3)
    o = np.concatenate([origins, ao])
    d = np.concatenate([d / np.linalg.norm(d, axis=1, keepdims=True), ad])
    data = data_of(INPUTS[name])
    recorder = AllSlots(geometry_from(data, traversal="wide4", leaves="packets"))
    got, ref = recorder.trace(o, d), recorder.all_slots(o, d)
    assert_same_hits(got, ref, data, d, 0 if name == "at_one_point" else n // 2)
    if name == "at_one_point":
        assert (got[1] < 0).all(), "triangles of zero area are never hit"
    scalar = recorder.trace(o, d, brute=True)
    flipped = (got[1] >= 0) != (scalar[1] >= 0)
    assert flipped.mean() <= (0.005 if name == "far_from_origin" else 0.0005), flipped.sum()
    both = (got[1] >= 0) & (got[1] == scalar[1])
    assert both.sum() >= 0.99 * (scalar[1] >= 0).sum() - flipped.sum()


def test_instanced_scene_finds_the_scalar_layouts_hits():
    """Packets of the world's and the instanced mesh's slots (a leaf's mask keeps it to its own
    mesh's lanes, which the other frame would misplace): the primitive and instance the scalar
    layout finds, t within rounding."""
    rng = np.random.default_rng(9)
    instanced, _, _, _ = paired_scenes(rng, loose=40)
    o, d = instancing_rays(rng, 20000)
    got = HitProbe(geometry_from(instanced, traversal="wide4", leaves="packets")).shoot(o, d)
    ref = HitProbe(geometry_from(instanced, traversal="wide4")).shoot(o, d)
    same = same_instanced_hits(got, ref)
    t = ref[same, HitProbe.T]
    assert np.allclose(got[same, HitProbe.T], t, rtol=1e-5, atol=1e-6)


def test_alpha_coverage_decides_lane_by_lane_as_the_scalar_layout():
    """Four stacked BLEND triangles (alpha 0.3) in one packet: each ray takes the nearest one
    whose coverage lets it stop, the same one the scalar layout takes (coverage is a function of
    ray and primitive), and the share of rays passing all four is 0.7^4 (binomial z-test)."""
    base = np.array([[-1.0, -1.0, 0.0], [3.0, -1.0, 0.0], [-1.0, 3.0, 0.0]], np.float32)
    tris = np.stack([base + np.float32([0.0, 0.0, 0.1 * i]) for i in range(4)])
    data = MeshData(tri_vertices=tris, tri_material=np.zeros(4, np.int32))
    rng = np.random.default_rng(5)
    n = 40000
    o = np.concatenate([rng.uniform(-0.5, 0.5, (n, 2)), np.full((n, 1), 2.0)], axis=1)
    d = np.tile([0.0, 0.0, -1.0], (n, 1))
    packed = RayShooter(geometry_from(data, materials=blend_row(), traversal="wide4", leaves="packets"))
    scalar = RayShooter(geometry_from(data, materials=blend_row(), traversal="wide4"))
    got = packed.closest(o, d)[1]
    np.testing.assert_array_equal(got, scalar.closest(o, d)[1])
    assert set(np.unique(got)) == {-1, 0, 1, 2, 3}
    z = ((got < 0).mean() - 0.7**4) / np.sqrt(0.7**4 * (1 - 0.7**4) / n)
    assert abs(z) < 3.29, z  # two-sided, 0.1 %
    np.testing.assert_array_equal(packed.occluded(o, d) == 1, got >= 0)


# ------------------------------------------------------------------------------------------------
# whole renders


@pytest.mark.filterwarnings("ignore::renderer.output.image_io.NegativePixelsWarning")
# One whole scene (the ray-level tests above hold every hit of mixed, degenerate, instanced and
# cut-out inputs to brute force and to the scalar layout): quads, a triangle mesh, textures (shading
# reads the corners back from the packets) and an environment map.
@pytest.mark.parametrize("path", ["assets/scenes/textured.toml"])
def test_mesh_scene_renders_z_equal_to_the_scalar_leaves(path):
    """Independent renders (different seeds) agree by the suite's z-tests."""
    scalar = render(path, "wide4", 5, spp=16)
    packed = render(path, "wide4", 6, spp=16, leaves="packets")
    assert scalar[0].mean() > 0.01
    assert_agree(packed, scalar, ("packets", "scalar"))


def test_the_renderer_picks_packets_where_triangles_are_at_least_half_the_primitives():
    from renderer.renderer import leaf_layout

    tris = data_of(INPUTS["five"])
    quads = MeshData(tri_vertices=INPUTS["two"], tri_material=np.zeros(2, np.int32),
                     quads=np.zeros((3, 3, 3), np.float32), quad_material=np.zeros(3, np.int32))
    assert leaf_layout("auto", tris) == "packets"
    assert leaf_layout("auto", quads) == "scalar"
    assert leaf_layout("scalar", tris) == "scalar" and leaf_layout("packets", quads) == "packets"


def test_analytic_scenes_leave_their_leaf_sizes_to_sah():
    """Scalar leaves over mostly analytic primitives get no forced leaf size (SAH decides); scalar
    leaves of triangles keep theirs, packets theirs, and an explicit option wins everywhere."""
    from renderer.renderer import ANALYTIC_MAX_LEAF_SIZE, MAX_LEAF_SIZE, MeshOptions, max_leaf_size

    analytic = {"triangle": 2, "quad": 3}
    triangles = {"triangle": 5, "sphere": 1}
    default = MeshOptions()
    assert max_leaf_size(default, "scalar", analytic) == ANALYTIC_MAX_LEAF_SIZE == 1
    assert max_leaf_size(default, "scalar", triangles) == MAX_LEAF_SIZE["scalar"]
    assert max_leaf_size(default, "packets", analytic) == MAX_LEAF_SIZE["packets"]
    assert max_leaf_size(default, "scalar") == MAX_LEAF_SIZE["scalar"]  # counts unknown
    assert max_leaf_size(MeshOptions(max_leaf_size=6), "scalar", analytic) == 6

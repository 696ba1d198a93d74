"""Packets of rays through the wide BVH (renderer/packets/traversal.py) find what one ray at a
time finds: the same closest primitive at the same distance, the same blockers, on random and
coherent rays, for every leaf layout and width; rays through shared edges never pass."""
import numpy as np
import pytest
import trimesh

from renderer.geometry.interface import INF
from renderer.geometry.mesh_data import MeshData
from tests.geometry.mesh_helpers import RayShooter, geometry_from
from tests.geometry.test_traversal import random_rays
from renderer.bench.packet_rays import PacketShooter


def packet_scene(rng, triangles=500):
    """Random triangles, spheres and quads (the kinds packets test) overlapping in one box."""
    centres = rng.uniform(-2, 2, (triangles, 1, 3))
    tris = centres + rng.normal(0, 0.25, (triangles, 3, 3))
    spheres = np.concatenate([rng.uniform(-2, 2, (20, 3)), rng.uniform(0.05, 0.4, (20, 1))], axis=1)
    quads = np.stack([rng.uniform(-2, 2, (15, 3)), rng.normal(0, 0.5, (15, 3)), rng.normal(0, 0.5, (15, 3))], axis=1)
    return MeshData(tri_vertices=tris.astype(np.float32), tri_material=np.zeros(triangles, np.int32),
                    spheres=spheres.astype(np.float32), sphere_material=np.zeros(20, np.int32),
                    quads=quads.astype(np.float32), quad_material=np.zeros(15, np.int32))


def coherent_rays(n, width):
    """Rays from one eye through a grid, `width` neighbours a packet (as camera rays)."""
    side = int(np.sqrt(n))
    u, v = np.meshgrid(np.linspace(-0.6, 0.6, side), np.linspace(-0.6, 0.6, side))
    d = np.stack([u.ravel(), v.ravel(), -np.ones(side * side)], axis=1)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.tile([0.0, 0.0, 6.0], (len(d), 1)), d


@pytest.fixture(scope="module")
def scene():
    return packet_scene(np.random.default_rng(3))


def assert_same_closest(a, b):
    (t_a, prim_a), (t_b, prim_b) = a, b
    assert (prim_a >= 0).sum() > 500, "the rays must actually hit things"
    np.testing.assert_array_equal(prim_a >= 0, prim_b >= 0)
    differ = prim_a != prim_b
    # another primitive only where two lie at the same distance (a tie the order decides)
    np.testing.assert_allclose(t_a[differ], t_b[differ], rtol=1e-5, atol=1e-6)
    assert differ.mean() < 1e-3
    # the same distance to the rounding of coordinates of magnitude ~2 (fast math may order a
    # triangle test's sums otherwise in another kernel)
    hit = prim_a >= 0
    np.testing.assert_allclose(t_a[hit], t_b[hit], rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("traversal", ["wide4", "wide8"])
@pytest.mark.parametrize("leaves", ["scalar", "packets"])
@pytest.mark.parametrize("width", [8, 16])
def test_packets_find_the_scalar_traversals_hits(scene, traversal, leaves, width):
    geometry = geometry_from(scene, traversal=traversal, leaves=leaves, leaf=8 if leaves == "packets" else 4)
    scalar, packets = RayShooter(geometry), PacketShooter(geometry, width)
    for o, d in (random_rays(np.random.default_rng(4), 6000), coherent_rays(4096, width)):
        assert_same_closest(packets.closest(o, d), scalar.closest(o, d))
        for t_max in (INF, 1.5):
            np.testing.assert_array_equal(packets.occluded(o, d, t_max), scalar.occluded(o, d, t_max))


def test_rays_one_lane_at_a_time_find_the_scalar_traversals_hits(scene):
    """traversal.trace_lanes (a large world's bounce and shadow rays) is the scalar walk per lane:
    the same primitives and distances, and lanes that are not rays skipped."""
    geometry = geometry_from(scene, traversal="wide8")
    scalar, lanes = RayShooter(geometry), PacketShooter(geometry, 4, one_at_a_time=True)
    for o, d in (random_rays(np.random.default_rng(5), 3000), coherent_rays(1024, 4)):
        (t_a, prim_a), (t_b, prim_b) = lanes.closest(o, d), scalar.closest(o, d)
        np.testing.assert_array_equal(prim_a, prim_b)
        np.testing.assert_allclose(t_a[prim_a >= 0], t_b[prim_b >= 0], rtol=1e-6)
        for t_max in (INF, 1.5):
            np.testing.assert_array_equal(lanes.occluded(o, d, t_max), scalar.occluded(o, d, t_max))
    o, d = coherent_rays(64, 4)
    _, prim = lanes._run(o, d, np.where(np.arange(len(o)) % 2 == 0, INF, -1.0), False)
    assert (prim[0::2] >= 0).any() and (prim[1::2] == -1).all()


def test_rays_that_are_not_rays_hit_nothing(scene):
    """A lane with t_max < 0 (a finished path) finds nothing, however much lies ahead of it."""
    geometry = geometry_from(scene, traversal="wide8")
    o, d = coherent_rays(64, 8)
    shooter = PacketShooter(geometry)
    _, prim = shooter._run(o, d, np.where(np.arange(len(o)) % 2 == 0, INF, -1.0), False)
    assert (prim[0::2] >= 0).any()
    assert (prim[1::2] == -1).all()


def test_no_ray_passes_between_triangles_sharing_an_edge():
    """Rays from inside a closed mesh, aimed at its vertices and edge midpoints (where two or more
    triangles meet) and at random, all hit it: the packet test is watertight as the scalar one."""
    mesh = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    tri = mesh.vertices[mesh.faces]
    data = MeshData(tri_vertices=tri.astype(np.float32), tri_material=np.zeros(len(tri), np.int32))
    edges = mesh.vertices[mesh.edges_unique]
    rng = np.random.default_rng(5)
    targets = np.concatenate([mesh.vertices, edges.mean(axis=1), rng.normal(size=(4000, 3))])
    origins = np.tile([0.01, -0.02, 0.015], (len(targets), 1))
    d = targets - origins
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    for leaves in ("scalar", "packets"):
        _, prim = PacketShooter(geometry_from(data, traversal="wide8", leaves=leaves)).closest(origins, d)
        assert (prim >= 0).all(), f"{(prim < 0).sum()} rays passed through the mesh ({leaves} leaves)"

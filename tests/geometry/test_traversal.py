"""BVH traversal equals brute force; shadow rays agree; the watertight test leaves no cracks;
spawned rays never find their own surface."""
import numpy as np
import pytest
import trimesh

from renderer.geometry.interface import INF
from renderer.geometry.mesh_data import MeshData
from tests.geometry.mesh_helpers import RayShooter, geometry_from, trimesh_data


def mixed_scene(rng, triangles=600):
    """Random triangles plus a few spheres, quads and discs, overlapping in one box."""
    centres = rng.uniform(-2, 2, (triangles, 1, 3))
    tris = centres + rng.normal(0, 0.25, (triangles, 3, 3))
    spheres = np.concatenate([rng.uniform(-2, 2, (20, 3)), rng.uniform(0.05, 0.4, (20, 1))], axis=1)
    quads = np.stack([rng.uniform(-2, 2, (15, 3)), rng.normal(0, 0.5, (15, 3)), rng.normal(0, 0.5, (15, 3))], axis=1)
    normals = rng.normal(size=(10, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    discs = np.concatenate([rng.uniform(-2, 2, (10, 3)), normals, rng.uniform(0.1, 0.5, (10, 1))], axis=1)
    return MeshData(tri_vertices=tris.astype(np.float32), tri_material=np.zeros(triangles, np.int32),
                    spheres=spheres.astype(np.float32), sphere_material=np.zeros(20, np.int32),
                    quads=quads.astype(np.float32), quad_material=np.zeros(15, np.int32),
                    discs=discs.astype(np.float32), disc_material=np.zeros(10, np.int32))


def random_rays(rng, n, spread=4.0):
    origins = rng.uniform(-spread, spread, (n, 3))
    targets = rng.uniform(-2, 2, (n, 3))
    d = targets - origins
    return origins, d / np.linalg.norm(d, axis=1, keepdims=True)


@pytest.fixture(scope="module")
def scene_and_rays():
    rng = np.random.default_rng(1)
    return mixed_scene(rng), random_rays(rng, 20000)


@pytest.mark.parametrize("strategy", ["sah", "midpoint", "equal_count"])
@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_traversal_equals_brute_force(scene_and_rays, strategy, traversal):
    data, (o, d) = scene_and_rays
    shooter = RayShooter(geometry_from(data, strategy=strategy, traversal=traversal))
    t, prim = shooter.closest(o, d)
    t_ref, prim_ref = shooter.closest(o, d, brute=True)
    assert (prim >= 0).sum() > 1000, "the rays must actually hit things"
    # Identical primitive tests in both, so results agree exactly except where two primitives
    # are hit at the very same distance (then either is right).
    same = (prim == prim_ref) | (np.abs(t - t_ref) <= 1e-6 * np.maximum(1.0, np.abs(t_ref)))
    assert same.all(), f"{(~same).sum()} rays differ"
    shadow = shooter.occluded(o, d, 1.5)
    assert np.array_equal(shadow == 1, t_ref < 1.5)


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_trace_stops_shadow_rays_at_the_first_hit(scene_and_rays, traversal):
    """geometry.trace with a per-ray flag (what the path tracer calls for every ray): flagged rays
    report the same occlusion as closest-hit rays but never test more primitives, and in total
    far fewer; unflagged rays are the closest-hit search."""
    data, (o, d) = scene_and_rays
    shooter = RayShooter(geometry_from(data, traversal=traversal))
    n = len(o)
    hit_any, tests_any = shooter.trace(o, d, 3.0, np.ones(n))
    hit_closest, tests_closest = shooter.trace(o, d, 3.0, np.zeros(n))
    t_ref, _ = shooter.closest(o, d)
    assert np.array_equal(hit_any, hit_closest) and np.array_equal(hit_closest == 1, t_ref < 3.0)
    assert (tests_any <= tests_closest).all() and tests_any.sum() < 0.9 * tests_closest.sum()
    mixed = (np.arange(n) % 2).astype(np.int32)
    hit_mixed, tests_mixed = shooter.trace(o, d, 3.0, mixed)
    assert np.array_equal(hit_mixed, hit_closest)
    assert np.array_equal(tests_mixed, np.where(mixed == 1, tests_any, tests_closest))


def edge_and_vertex_rays(mesh, rng, per_edge=40):
    """Rays from outside aimed exactly at points on edges (shared by two faces) and at vertices."""
    v = np.asarray(mesh.vertices, np.float64)
    edges = np.asarray(mesh.edges_unique)
    s = rng.uniform(0, 1, (len(edges), per_edge, 1))
    targets = (v[edges[:, 0]][:, None] * (1 - s) + v[edges[:, 1]][:, None] * s).reshape(-1, 3)
    targets = np.concatenate([targets, v])
    # Origins on a big sphere around the mesh, on the target's side: directions span all angles.
    centre = v.mean(axis=0)
    radius = np.linalg.norm(v - centre, axis=1).max() * 3
    outward = targets - centre + rng.normal(0, 0.3 * radius, targets.shape)
    outward /= np.linalg.norm(outward, axis=1, keepdims=True)
    origins = centre + outward * radius
    d = targets - origins
    o32 = origins.astype(np.float32)
    d32 = (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)
    # Keep rays whose line passes within the inscribed sphere: they cross the solid for sure, so a
    # miss can only be a crack. (A ray merely touching the convex silhouette at an edge may
    # legitimately miss after rounding.) In float32 the target is exactly on the edge only up to
    # the rounding of the inputs; the watertight test must still never let a ray through.
    face_centres = v[np.asarray(mesh.faces)].mean(axis=1)
    inradius = np.abs(((face_centres - centre) * np.asarray(mesh.face_normals)).sum(axis=1)).min()
    o64, d64 = o32.astype(np.float64), d32.astype(np.float64)
    along = ((centre - o64) * d64).sum(axis=1, keepdims=True)
    approach = np.linalg.norm(o64 + along * d64 - centre, axis=1)
    keep = approach < 0.98 * inradius
    return o32[keep], d32[keep]


@pytest.mark.parametrize("transform, traversal, leaves", [("identity", "stack", "scalar"),
                                                         ("rotated_scaled_moved", "stack", "scalar"),
                                                         ("identity", "wide4", "packets"),
                                                         ("rotated_scaled_moved", "wide4", "packets"),
                                                         ("rotated_scaled_moved", "wide8", "packets")])
def test_watertight_no_ray_passes_through_shared_edges_or_vertices(transform, traversal, leaves):
    rng = np.random.default_rng(2)
    mesh = trimesh.creation.icosphere(subdivisions=3)
    if transform != "identity":
        m = trimesh.transformations.random_rotation_matrix(rng.uniform(size=3))
        m[:3, :3] *= 37.0
        m[:3, 3] = [1234.5, -250.25, 88.0]
        mesh.apply_transform(m)
    shooter = RayShooter(geometry_from(trimesh_data(mesh), traversal=traversal, leaves=leaves))
    o, d = edge_and_vertex_rays(mesh, rng)
    assert len(o) > 50000
    o = np.tile(o, (17, 1))  # over a million rays per case (jittered copies of the aimed rays)
    d = np.tile(d, (17, 1)) + rng.normal(0, 1e-7, (len(o), 3)).astype(np.float32)
    assert len(o) >= 1_000_000
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    t, prim = shooter.closest(o, d)
    misses = int((prim < 0).sum())
    assert misses == 0, f"{misses} of {len(o)} rays slipped through the closed mesh"


@pytest.mark.parametrize("scale", [1e-3, 1e-1, 1.0, 1e2, 1e4])
@pytest.mark.parametrize("offset", [0.0, 1e2, 1e4])
@pytest.mark.parametrize("traversal, leaves", [("stack", "scalar"), ("wide4", "packets"), ("wide4", "scalar"), ("stack", "packets"),
                                               ("wide8", "packets")])
def test_spawned_rays_never_hit_their_own_surface(scale, offset, traversal, leaves):
    # float32 spacing at |offset| is offset * 2^-23; an object a few ulps across cannot be
    # represented at all (1 mm at 10 km is 1 ulp), so such pairs are not meaningful cases.
    ulps_across = scale / (max(offset, scale) * 2.0**-23)
    if ulps_across < 500:
        pytest.skip(f"a {scale} m object at {offset} m spans only {ulps_across:.0f} float32 ulps")
    rng = np.random.default_rng(3)
    mesh = trimesh.creation.icosphere(subdivisions=2)
    mesh.apply_scale(scale)
    mesh.apply_translation([offset, -offset * 0.5, offset * 0.25])
    geometry = geometry_from(trimesh_data(mesh), traversal=traversal, leaves=leaves)
    shooter = RayShooter(geometry)
    n = 20000
    centre = np.asarray(mesh.vertices).mean(axis=0)
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    origins = centre - dirs * 3 * scale
    # Leaving outward: on a convex closed mesh nothing may be hit again.
    out = rng.normal(size=(n, 3))
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    out = np.where((out * dirs).sum(axis=1, keepdims=True) > 0, -out, out)  # towards the outside
    prim, second, _ = shooter.respawn(origins, dirs, out)
    hits_outward = prim >= 0
    assert hits_outward.mean() > 0.99
    # A reflected ray must be on the outside of the hit face: measure against the face normal.
    # Rounding the vertices to float32 tilts faces by up to ~2 ulp / edge length radians, so the
    # stored mesh is convex only to that angle: leave out directions closer to tangent than that.
    ulp = float(np.spacing(np.float32(np.abs(mesh.vertices).max())))
    tilt = 4 * ulp / float(mesh.edges_unique_length.min())
    faces = np.asarray(mesh.face_normals)[prim[hits_outward]]
    outside = (faces * out[hits_outward]).sum(axis=1) > 1e-3 + tilt
    assert np.all(second[hits_outward][outside] == -1), "an outward spawned ray hit the mesh again"
    # Going inward (as a refracted ray does), the ray must reach the far side, not its own face.
    prim, second, t = shooter.respawn(origins, dirs, dirs)
    ok = prim >= 0
    assert np.all(second[ok] != prim[ok]) and np.all(second[ok] >= 0)
    assert np.all(t[ok] > 1e-3 * scale)

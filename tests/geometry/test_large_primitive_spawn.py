"""Rays leaving a primitive never find it again, however large it is against the point they leave.

A surface point is computed from the primitive's coordinates (centre + radius * normal for a
sphere, corners and barycentrics for a triangle, corner and edges for a quad), so it rounds at
their magnitude, while offset_ray_origin moves it by ulps of the point's own. Where the two differ
the spawned ray could start inside the primitive: the weekend scene's ground (a sphere of radius
1000 about (0, -1000, 0)) has points near y = 0 with errors of ~1e-4, and a quarter of the rays
leaving it hit it again ~6e-5 away; a tilted ground quad or triangle pair 2 km across lost 6 % of
its light near its middle, 14 % at 20 km (tests/render/test_ground_furnace.py sees that in whole
images). tests/geometry/test_traversal.py tests meshes whose points are as large as their
corners; here the points are much smaller than the coordinates they come from.

Each primitive is hit from outside at incidences up to 84 degrees; rays spawned back to the side
they came from must escape, and rays spawned on through it must reach a sphere's far side or, for
a flat primitive, nothing.
"""
import numpy as np
import pytest

from renderer.geometry.mesh_data import MeshData
from tests.geometry.mesh_helpers import RayShooter, geometry_from, tilt, tilted_square_corners

# (centre, radius): small and unit spheres, grounds as large as the weekend's and ten times larger,
# a sphere about the origin and one far from it.
SPHERES = {
    "small_off_origin": ((5.0, 3.0, -2.0), 0.2),
    "unit_ground": ((0.0, -1.0, 0.0), 1.0),
    "weekend_ground": ((0.0, -1000.0, 0.0), 1000.0),
    "10km_ground": ((0.0, -1e4, 0.0), 1e4),
    "10km_about_origin": ((0.0, 0.0, 0.0), 1e4),
    "unit_10km_away": ((1e4, 0.0, 0.0), 1.0),
}
FLAT_SIZES = (1.0, 2e3, 2e4)  # metres across, centred on the origin
RAYS = 50_000
MIN_COSINE = 0.1  # incidence of the first rays, and how far from tangent the spawned rays leave
NO_MATERIAL = np.zeros(0, np.int32)


def sphere_data(centre, radius):
    return MeshData(tri_vertices=np.zeros((0, 3, 3), np.float32), tri_material=NO_MATERIAL,
                    spheres=np.array([[*centre, radius]], np.float32), sphere_material=np.zeros(1, np.int32))


def flat_data(kind, size):
    """A square `size` across in the plane through the origin, tilted: one quad, or two triangles."""
    corners = tilted_square_corners(size)
    if kind == "quad":
        quad = np.stack([corners[0], corners[1] - corners[0], corners[3] - corners[0]])[None]
        return MeshData(tri_vertices=np.zeros((0, 3, 3), np.float32), tri_material=NO_MATERIAL,
                        quads=quad.astype(np.float32), quad_material=np.zeros(1, np.int32))
    triangles = np.stack([corners[[0, 2, 1]], corners[[0, 3, 2]]])
    return MeshData(tri_vertices=triangles.astype(np.float32), tri_material=np.zeros(2, np.int32))


def aimed_rays(rng, points, normals, scale):
    """Rays from outside onto `points` (outward `normals`), at incidences whose cosine is at least
    MIN_COSINE, starting 0.1-3 `scale` away."""
    n = len(points)
    d = -normals + rng.normal(size=(n, 3)) * 0.5
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d = np.where((d * normals).sum(axis=1, keepdims=True) > -MIN_COSINE, -normals, d)
    return points - d * rng.uniform(0.1, 3.0, (n, 1)) * scale, d


def leaving_directions(rng, normals):
    """Random directions on the outer side of `normals`, at least MIN_COSINE from tangent."""
    out = rng.normal(size=normals.shape)
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    out = np.where((out * normals).sum(axis=1, keepdims=True) < 0.0, -out, out)
    return out, (out * normals).sum(axis=1) > MIN_COSINE


def assert_never_hit_again(second, t, leaving):
    again = leaving & (second >= 0)
    assert not again.any(), (f"{again.sum()} of {leaving.sum()} rays leaving the primitive hit it again "
                             f"(median t {np.median(t[again]):.3g})")


@pytest.mark.parametrize("name", SPHERES)
def test_rays_leaving_a_sphere_never_hit_it_again(name):
    centre, radius = SPHERES[name]
    rng = np.random.default_rng(11)
    shooter = RayShooter(geometry_from(sphere_data(centre, radius)))
    # Points on a cap: the upper half of small spheres, within 20 m of the top of large ones.
    theta = rng.uniform(0.0, min(20.0 / radius, 1.4), RAYS)
    phi = rng.uniform(0.0, 2.0 * np.pi, RAYS)
    normal = np.stack([np.sin(theta) * np.cos(phi), np.cos(theta), np.sin(theta) * np.sin(phi)], axis=1)
    origins, dirs = aimed_rays(rng, np.asarray(centre) + radius * normal, normal, max(radius, 1.0))
    out, leaving = leaving_directions(rng, normal)
    prim, second, t = shooter.respawn(origins, dirs, out)
    assert np.all(prim == 0), "a ray aimed at the sphere missed it"
    assert_never_hit_again(second, t, leaving)
    # Inward, as a refracted ray goes on: the far side, past the middle of the chord (a hit on its
    # own side would come at t ~ 0; the chord itself moves with the spawn offset at grazing angles).
    prim, second, t = shooter.respawn(origins, dirs, dirs)
    assert np.all(second == 0), "a ray spawned into the sphere did not reach its far side"
    chord = 2.0 * radius * (-(dirs * normal).sum(axis=1))
    assert np.all(t > 0.5 * chord), "a ray spawned into the sphere hit its own side"


@pytest.mark.parametrize("size", FLAT_SIZES, ids=lambda s: f"{s:g}m")
@pytest.mark.parametrize("kind, traversal, leaves", [("quad", "stack", "scalar"), ("triangles", "stack", "scalar"),
                                                     ("triangles", "wide8", "packets")])
def test_rays_leaving_a_large_flat_primitive_never_hit_it_again(kind, traversal, leaves, size):
    """Triangles also through the renderer's default traversal (8-wide nodes, 4-lane packet
    leaves), whose triangle test rounds on its own."""
    rng = np.random.default_rng(12)
    shooter = RayShooter(geometry_from(flat_data(kind, size), traversal=traversal, leaves=leaves))
    # Points within 10 m of the middle (within the square for the 1 m one), from both sides.
    reach = min(10.0, 0.45 * size)
    rotation = tilt()
    xz = rng.uniform(-reach, reach, (RAYS, 2))
    points = np.stack([xz[:, 0], np.zeros(RAYS), xz[:, 1]], axis=1) @ rotation.T
    up = rotation @ np.array([0.0, 1.0, 0.0])
    normal = np.where(rng.uniform(size=(RAYS, 1)) < 0.5, up, -up)
    origins, dirs = aimed_rays(rng, points, normal, 1.0)
    out, leaving = leaving_directions(rng, normal)
    prim, second, t = shooter.respawn(origins, dirs, out)
    assert np.all(prim >= 0), "a ray aimed at the primitive missed it"
    assert_never_hit_again(second, t, leaving)
    # On through it (a thin sheet of glass): nothing lies beyond.
    prim, second, t = shooter.respawn(origins, dirs, dirs)
    assert np.all(second == -1), "a ray spawned through the primitive hit it again"

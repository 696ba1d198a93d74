"""Test helpers: mesh geometries built from numpy data, and kernels that fire rays at them."""
import numpy as np
import taichi as ti
import trimesh

from renderer.bench.ray_batch import RayBatch, ray_at
from renderer.geometry.instance_bvh import build_scene_bvh
from renderer.geometry.interface import INF
from renderer.geometry.intersect import watertight_setup
from renderer.geometry.mesh_data import MeshData
from renderer.geometry.mesh_geometry import MeshGeometry


def geometry_from(data: MeshData, strategy="sah", traversal="stack", triangle_test="watertight", leaf=4,
                  materials=None, leaves="scalar"):
    bvh = build_scene_bvh(data, strategy=strategy, max_leaf_size=leaf)
    return MeshGeometry(data, bvh, traversal=traversal, triangle_test=triangle_test, materials=materials,
                        leaves=leaves)


# Euler angles, degrees, about x, then y, then z (the scene files' `rotate`): a plane tilted so
# that no coordinate of its points is exact.
TILT_DEGREES = (7.0, 0.0, 5.0)


def tilt(tilt_degrees=TILT_DEGREES) -> np.ndarray:
    """The 3x3 rotation of `tilt_degrees`."""
    return trimesh.transformations.euler_matrix(*np.radians(tilt_degrees), axes="sxyz")[:3, :3]


def tilted_square_corners(size: float) -> np.ndarray:
    """The four corners (4, 3) of a square `size` across about the origin in the xz plane, tilted
    by TILT_DEGREES."""
    h = 0.5 * size
    return np.array([[-h, 0.0, -h], [h, 0.0, -h], [h, 0.0, h], [-h, 0.0, h]]) @ tilt().T


def trimesh_data(mesh, material=0) -> MeshData:
    tris = np.asarray(mesh.vertices, np.float64)[np.asarray(mesh.faces)]
    return MeshData(tri_vertices=tris.astype(np.float32), tri_material=np.full(len(tris), material, np.int32))


@ti.data_oriented
class RayShooter:
    """Closest hits (or any-hit flags) of many rays, by the BVH (the benchmark's RayBatch) or by
    brute force."""

    def __init__(self, geometry: MeshGeometry):
        self.geometry = geometry
        self.batch = RayBatch(geometry)

    @ti.kernel
    def _brute_closest(self, o: ti.types.ndarray(), d: ti.types.ndarray(), out_t: ti.types.ndarray(),
                       out_prim: ti.types.ndarray()):
        for i in range(o.shape[0]):
            ray = ray_at(o, d, i)
            t = INF
            prim = -1
            k, s = watertight_setup(ray.d)
            for g in range(self.geometry.prim_material.shape[0]):
                h, th, b1, b2 = self.geometry._test_prim(g, ray.o, ray.d, k, s, t)
                if h == 1:
                    t = th
                    prim = g
            out_t[i] = t
            out_prim[i] = prim

    def closest(self, origins, directions, brute=False):
        """(t, prim) of each ray's closest hit; a miss has t = INF and prim -1."""
        n = len(origins)
        o, d = np.ascontiguousarray(origins, np.float32), np.ascontiguousarray(directions, np.float32)
        t = np.zeros(n, np.float32)
        prim = np.zeros(n, np.int32)
        if brute:
            self._brute_closest(o, d, t, prim)
        else:
            self.batch.closest(o, d, np.full(n, INF, np.float32), t, prim, np.zeros((n, 2), np.int32))
            t[prim < 0] = INF
        return t, prim

    def occluded(self, origins, directions, t_max=INF):
        out = np.zeros(len(origins), np.int32)
        self.batch.occluded(np.ascontiguousarray(origins, np.float32), np.ascontiguousarray(directions, np.float32),
                            np.full(len(origins), t_max, np.float32), out)
        return out

    @ti.kernel
    def _trace(self, o: ti.types.ndarray(), d: ti.types.ndarray(), t_max: ti.f32, any_hit: ti.types.ndarray(),
               out_hit: ti.types.ndarray(), out_tests: ti.types.ndarray()):
        for i in range(o.shape[0]):
            ray = ray_at(o, d, i)
            hit = self.geometry.trace(ray, t_max, any_hit[i] == 1)
            out_hit[i] = hit.hit
            out_tests[i] = hit.tests

    def trace(self, origins, directions, t_max, any_hit):
        """(hit flags, primitive tests) of geometry.trace with a per-ray any_hit flag."""
        n = len(origins)
        hits, tests = np.zeros(n, np.int32), np.zeros(n, np.int32)
        self._trace(np.ascontiguousarray(origins, np.float32), np.ascontiguousarray(directions, np.float32), t_max,
                    np.ascontiguousarray(any_hit, np.int32), hits, tests)
        return hits, tests

    @ti.kernel
    def _respawn(self, o: ti.types.ndarray(), d: ti.types.ndarray(), d2: ti.types.ndarray(),
                 out_prim: ti.types.ndarray(), out_second: ti.types.ndarray(), out_t: ti.types.ndarray()):
        """Hit, then spawn a ray from the hit point in direction d2 and report what it hits."""
        for i in range(o.shape[0]):
            ray = ray_at(o, d, i)
            hit = self.geometry.intersect(ray, INF)
            out_prim[i] = -1
            out_second[i] = -2
            if hit.hit == 1:
                s = self.geometry.surface(ray, hit)
                out_prim[i] = hit.prim
                second = self.geometry.intersect(self.geometry.spawn(s, ti.math.vec3(d2[i, 0], d2[i, 1], d2[i, 2])), INF)
                out_second[i] = second.prim if second.hit == 1 else -1
                out_t[i] = second.t

    def respawn(self, origins, directions, new_directions):
        n = len(origins)
        prim = np.zeros(n, np.int32)
        second = np.zeros(n, np.int32)
        t = np.zeros(n, np.float32)
        self._respawn(np.ascontiguousarray(origins, np.float32), np.ascontiguousarray(directions, np.float32),
                      np.ascontiguousarray(new_directions, np.float32), prim, second, t)
        return prim, second, t


@ti.data_oriented
class SurfaceProbe:
    """Closest hits of any geometry (mesh or SDF) with what its surface() makes of them, one row
    per ray: hit, t, prim (surface().prim: a mesh primitive or an SDF node), bary (2), p (3),
    n_geo (3), uv (2), tangent (4), front_face, n_shading (3). Column slices are the class
    constants below."""

    HIT, T, PRIM, BARY, P, N_GEO, UV, TANGENT, FRONT, N_SHADING = (
        0, 1, 2, slice(3, 5), slice(5, 8), slice(8, 11), slice(11, 13), slice(13, 17), 17, slice(18, 21))
    WIDTH = 21

    def __init__(self, geometry):
        self.geometry = geometry

    @ti.kernel
    def _shoot(self, o: ti.types.ndarray(), d: ti.types.ndarray(), out: ti.types.ndarray()):
        for i in range(o.shape[0]):
            ray = ray_at(o, d, i)
            h = self.geometry.intersect(ray, INF)
            out[i, 0] = h.hit
            if h.hit == 1:
                s = self.geometry.surface(ray, h)
                out[i, 1] = h.t
                out[i, 2] = s.prim
                out[i, 3] = h.bary.x
                out[i, 4] = h.bary.y
                for k in ti.static(range(3)):
                    out[i, 5 + k] = s.p[k]
                    out[i, 8 + k] = s.n_geo[k]
                    out[i, 18 + k] = s.n_shading[k]
                out[i, 11] = s.uv.x
                out[i, 12] = s.uv.y
                for k in ti.static(range(4)):
                    out[i, 13 + k] = s.tangent[k]
                out[i, 17] = s.front_face

    def shoot(self, o, d):
        out = np.zeros((len(o), self.WIDTH), np.float32)
        self._shoot(np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32), out)
        return out

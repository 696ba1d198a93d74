"""Kernels that fire numpy arrays of rays at one geometry: closest hits (distance, primitive, node
visits and primitive tests) and shadow-ray flags. The BVH benchmark times them; the geometry tests
hold traversal against brute force with them.
"""
# No `from __future__ import annotations`: Taichi reads the kernels' annotations as objects.
import numpy as np
import taichi as ti

from renderer.geometry.interface import Ray

MISS_T = -1.0  # the distance written for a ray that hits nothing


@ti.func
def ray_at(o: ti.template(), d: ti.template(), i):
    """Ray i of (N, 3) origin and direction arrays, without a cone (mesh geometry ignores it)."""
    return Ray(o=ti.math.vec3(o[i, 0], o[i, 1], o[i, 2]), d=ti.math.vec3(d[i, 0], d[i, 1], d[i, 2]),
               cone_width=0.0, cone_spread=0.0)


@ti.data_oriented
class RayBatch:
    """Closest hits and shadow flags of (N, 3) float32 ray arrays against one geometry.

    Each instance compiles its own kernels (Taichi specialises them on the geometry object)."""

    def __init__(self, geometry):
        self.geometry = geometry

    @ti.kernel
    def _closest(self, o: ti.types.ndarray(), d: ti.types.ndarray(), t_max: ti.types.ndarray(),
                 out_t: ti.types.ndarray(), out_prim: ti.types.ndarray(), out_stats: ti.types.ndarray()):
        for i in range(o.shape[0]):
            hit = self.geometry.intersect(ray_at(o, d, i), t_max[i])
            out_t[i] = hit.t if hit.hit == 1 else MISS_T
            out_prim[i] = hit.prim if hit.hit == 1 else -1
            out_stats[i, 0] = hit.work
            out_stats[i, 1] = hit.tests

    @ti.kernel
    def _occluded(self, o: ti.types.ndarray(), d: ti.types.ndarray(), t_max: ti.types.ndarray(),
                  out: ti.types.ndarray()):
        for i in range(o.shape[0]):
            out[i] = 1 if self.geometry.occluded(ray_at(o, d, i), t_max[i]) else 0

    def closest(self, origins: np.ndarray, directions: np.ndarray, t_max: np.ndarray, out_t: np.ndarray,
                out_prim: np.ndarray, out_stats: np.ndarray) -> None:
        """Closest hit within t_max per ray: out_t (MISS_T on a miss), out_prim (-1 on a miss),
        out_stats (N, 2) int32: node visits and primitive tests. Returns once the kernel is done."""
        self._closest(origins, directions, t_max, out_t, out_prim, out_stats)
        ti.sync()

    def occluded(self, origins: np.ndarray, directions: np.ndarray, t_max: np.ndarray, out: np.ndarray) -> None:
        """out[i] = 1 when anything lies on ray i within t_max[i] (the shadow-ray search), else 0."""
        self._occluded(origins, directions, t_max, out)
        ti.sync()

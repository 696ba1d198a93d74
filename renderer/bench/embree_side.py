"""Embree as the BVH benchmark's yardstick: the optional `embreex` package (`pip install embreex`,
or the project's `bench` extra) over the benchmark's meshes and rays, and the per-ray agreement of
Lantern's closest hits with Embree's.

embreex traces one ray at a time in a loop that releases the GIL, so the rays are cut into chunks
run by a pool of Python threads; Embree builds with its own thread pool over all cores. Nothing
here imports embreex at module import time; `load_embree()` says whether it is there.
"""
from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from renderer.bench.rays import Rays, ray_rates

AGREEMENT_RTOL = 1e-4  # relative distance tolerance of the cross-check against Embree


def load_embree():
    """(rtcore_scene module, TriangleMesh class, version text) or (None, None, reason)."""
    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except Exception as e:  # noqa: BLE001 - any import failure means: no Embree column
        return None, None, f"{type(e).__name__}: {e}"
    version = "embreex"
    try:
        from importlib.metadata import version as dist_version

        from embreex import rtcore

        version = f"{repr(rtcore.EmbreeDevice()).strip()} (embreex {dist_version('embreex')})"
    except Exception:  # noqa: BLE001 - informational only
        pass
    return rtcore_scene, TriangleMesh, version


class EmbreeMesh:
    """An Embree scene over the triangles; rays split into chunks over `threads` Python threads
    (embreex's ray loop releases the GIL)."""

    CHUNKS_PER_THREAD = 8  # dynamic load balance: camera rays that miss are cheap

    def __init__(self, rtcore_scene, triangle_mesh, tris: np.ndarray, threads: int, pool: ThreadPoolExecutor):
        t0 = time.perf_counter()
        try:
            self.scene = rtcore_scene.EmbreeScene(robust=True)
            self.robust = True
        except TypeError:  # an embreex without the flag
            self.scene = rtcore_scene.EmbreeScene()
            self.robust = None
        self._mesh = triangle_mesh(self.scene, np.ascontiguousarray(tris, np.float32))
        t1 = time.perf_counter()
        # The first query commits the scene: that is where Embree builds its BVH.
        self.scene.run(np.zeros((1, 3), np.float32), np.array([[0.0, 0.0, 1.0]], np.float32))
        self.upload_s = t1 - t0
        self.build_s = time.perf_counter() - t1
        self.threads = threads
        self.pool = pool

    def _chunks(self, n: int):
        k = max(1, min(n, self.threads * self.CHUNKS_PER_THREAD))
        edges = np.linspace(0, n, k + 1).astype(np.int64)
        return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:]) if b > a]

    def closest(self, rays: Rays, out_t: np.ndarray, out_prim: np.ndarray) -> None:
        def part(ab):
            a, b = ab
            r = self.scene.run(rays.origins[a:b], rays.directions[a:b], dists=np.array(rays.t_max[a:b]), output=1)
            out_t[a:b] = r["tfar"]
            out_prim[a:b] = r["primID"]
        list(self.pool.map(part, self._chunks(len(rays))))

    def occluded(self, rays: Rays, out: np.ndarray) -> None:
        def part(ab):
            a, b = ab
            r = self.scene.run(rays.origins[a:b], rays.directions[a:b], dists=np.array(rays.t_max[a:b]),
                               query="OCCLUDED")
            out[a:b] = np.asarray(r) >= 0  # embreex: 0 (a geometry id) when occluded, -1 when not
        list(self.pool.map(part, self._chunks(len(rays))))


class EmbreeClosestCall:
    def __init__(self, embree: EmbreeMesh, rays: Rays):
        self.embree = embree
        self.rays = rays
        self.t = np.zeros(len(rays), np.float32)
        self.prim = np.zeros(len(rays), np.int32)

    def __call__(self):
        self.embree.closest(self.rays, self.t, self.prim)

    @property
    def hit(self) -> np.ndarray:
        return self.prim >= 0

    def summary(self, timing) -> dict:
        return {**ray_rates(len(self.rays), timing), "hit_fraction": float(self.hit.mean())}


class EmbreeOccludedCall:
    def __init__(self, embree: EmbreeMesh, rays: Rays):
        self.embree = embree
        self.rays = rays
        self.out = np.zeros(len(rays), np.int32)

    def __call__(self):
        self.embree.occluded(self.rays, self.out)


def compare(lantern_t: np.ndarray, embree_t: np.ndarray, embree_hit: np.ndarray, rtol: float):
    """(agree, lantern hit, both hit, close, relative difference) per ray; Lantern misses have t < 0."""
    l_hit = lantern_t >= 0
    both = l_hit & embree_hit
    diff = np.abs(lantern_t.astype(np.float64) - embree_t.astype(np.float64))
    rel = np.where(both, diff / np.maximum(np.abs(embree_t.astype(np.float64)), 1e-30), 0.0)
    close = both & (rel <= rtol)
    return (~l_hit & ~embree_hit) | close, l_hit, both, close, rel


def agreement(lantern_t: np.ndarray, embree_t: np.ndarray, embree_hit: np.ndarray,
              rtol: float = AGREEMENT_RTOL) -> dict:
    """Per-ray agreement of closest hits: both miss, or both hit at distances within rtol."""
    agree, l_hit, both, close, rel = compare(lantern_t, embree_t, embree_hit, rtol)
    n = max(1, lantern_t.shape[0])
    return {"fraction": float(agree.sum() / n), "rays": int(lantern_t.shape[0]), "disagreeing": int((~agree).sum()),
            "lantern_only_hits": int((l_hit & ~embree_hit).sum()),
            "embree_only_hits": int((~l_hit & embree_hit).sum()),
            "distance_mismatches": int((both & ~close).sum()),
            "max_relative_difference": float(rel.max()) if rel.size else 0.0}

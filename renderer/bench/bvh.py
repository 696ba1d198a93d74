"""`python app.py bench bvh`: BVH build and traversal, side by side with Embree.

On three meshes (the bunny model, 5,648 triangles; a 100,352-triangle terrain; a 1,002,528-triangle
terrain), in one process so that ratios are meaningful:

1. Build: `build_bvh` seconds (median of repeats; the per-primitive boxes and centroids are
   computed once beforehand and timed apart) and triangles/s per split strategy (sah, midpoint,
   equal_count), the SAH cost of each tree, its node count and depth, and the bytes per triangle
   the BVH plus the triangle intersection data take on the device (`MeshGeometry.device_bytes()`).
   Issue targets: at most 64 bytes per triangle (the Renderer's configuration: SAH, leaves of 4),
   and the SAH build of the 1M mesh in at most 2 s.
2. Trace: closest-hit Mrays/s for every split strategy x traversal (stack, stackless) x triangle
   test (watertight, moller), on coherent rays (a pinhole camera grid on the mesh) and on
   incoherent rays (origins on a sphere around the mesh, aimed at uniform random points in its
   box), with the mean node visits and primitive tests per ray (`Hit.work`, `Hit.tests`).
   Any-hit (`occluded`) rays on the Renderer's configuration: the incoherent rays as segments
   ending at their random target points (shadow rays), against closest-hit on the same segments.
   Each configuration is compiled (first call, on a few rays) before timing; the timed calls run
   round-robin over all configurations of a mesh (and Embree), medians of several launches.
3. Embree (the optional `embreex` package: `pip install embreex`, or the project's `bench` extra)
   on the same meshes and the same rays: its build time (scene commit), Mrays/s, and the ratio
   Lantern / Embree on incoherent rays. Issue target: at least 0.3x Embree's rays/s on incoherent
   closest-hit rays, judged on the Renderer's configuration (sah, stack, watertight). Cross-check:
   the fraction of rays on which every Lantern configuration agrees with Embree (both miss, or
   both hit with distances within 1e-4 relative). Without embreex the Embree columns are skipped.
4. Leaf size: SAH builds with max_leaf_size 1, 2, 4, 8, 16 on the 100k mesh: build time, bytes per
   triangle, SAH cost and incoherent Mrays/s (stack, watertight).

Threads: Taichi's CPU back-end runs kernels on `cpu_max_num_threads` (all cores by default, 2 on
the machine this was written on). embreex traces one ray at a time in a loop that releases the
GIL, so the rays are cut into chunks run by as many Python threads as Taichi uses; Embree builds
with its own thread pool over all cores. Both thread counts are printed and stored.

Writes <out_dir>/bench_bvh.json and PNG plots next to it, and prints tables.
"""
# No `from __future__ import annotations`: Taichi reads the kernels' annotations as objects.
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from renderer.bench.common import (
    load_average,
    machine_info,
    print_table,
    pyplot,
    save_figure,
    time_call,
    time_interleaved,
    verdict,
    write_json,
    speed_runtime,
)

ROOT = Path(__file__).resolve().parents[2]
BUNNY = ROOT / "assets" / "models" / "bunny.glb"

BYTES_PER_TRIANGLE_TARGET = 64.0  # BVH + triangle intersection data on the device, per triangle
SAH_BUILD_TARGET_S = 2.0  # SAH build of the 1M-triangle mesh
SAH_BUILD_TARGET_MIN_TRIANGLES = 1_000_000
EMBREE_RATIO_TARGET = 0.3  # Lantern / Embree incoherent closest-hit rays per second
AGREEMENT_RTOL = 1e-4  # relative distance tolerance of the cross-check against Embree
FAR = 1e30  # t_max of closest-hit rays (the geometry interface's INF)

STRATEGIES = ("sah", "midpoint", "equal_count")
TRAVERSALS = ("stack", "stackless")
TRIANGLE_TESTS = ("watertight", "moller")
DEFAULT = ("sah", "stack", "watertight")  # the Renderer's MeshOptions
DEFAULT_LEAF = 4  # the Renderer's MeshOptions.max_leaf_size
# Leaf sizes whose rays/s lie within this fraction of the best are reported as ties: run-to-run
# noise on a shared machine is a few per cent.
LEAF_TIE = 0.03


@dataclass(frozen=True)
class MeshSpec:
    """A benchmark mesh: the bunny model file, or a generated terrain or icosphere."""

    name: str
    kind: str  # "model", "terrain" or "icosphere"
    params: tuple = ()  # generator parameters as (name, value) pairs; for "model": (("path", p),)

    def load(self) -> np.ndarray:
        """Triangle corners (T, 3, 3) float32, world space."""
        if self.kind == "model":
            from renderer.scene.model_formats import load_mesh_asset

            asset = load_mesh_asset(dict(self.params).get("path", BUNNY))
            return np.concatenate([np.asarray(m.positions, np.float32)[np.asarray(m.indices)]
                                   for m in asset.meshes]).astype(np.float32)
        from renderer.scene.generators import generate

        positions, indices, _ = generate(self.kind, dict(self.params))
        return np.ascontiguousarray(positions[indices], np.float32)


MESHES = (
    MeshSpec("bunny-5k", "model", (("path", str(BUNNY)),)),
    MeshSpec("terrain-100k", "terrain", (("resolution", 224),)),
    MeshSpec("terrain-1m", "terrain", (("resolution", 708),)),
)


@dataclass(frozen=True)
class BvhBenchConfig:
    meshes: tuple = MESHES
    build_runs: int = 3
    build_runs_large: int = 3  # for meshes of at least SAH_BUILD_TARGET_MIN_TRIANGLES
    camera: tuple = (512, 512)
    incoherent_rays: int = 1 << 18
    trace_runs: int = 7
    strategies: tuple = STRATEGIES
    traversals: tuple = TRAVERSALS
    triangle_tests: tuple = TRIANGLE_TESTS
    shadow_rays: bool = True
    embree: bool = True
    leaf_mesh: str = "terrain-100k"
    leaf_sizes: tuple = (1, 2, 4, 8, 16)
    seed: int = 1


FULL = BvhBenchConfig()
QUICK = BvhBenchConfig(build_runs=2, build_runs_large=1, camera=(256, 256), incoherent_rays=1 << 16,
                       trace_runs=3)


# --- rays --------------------------------------------------------------------------------------

@dataclass
class Rays:
    origins: np.ndarray  # (N, 3) f32
    directions: np.ndarray  # (N, 3) f32, unit
    t_max: np.ndarray  # (N,) f32

    def __len__(self) -> int:
        return int(self.origins.shape[0])

    def head(self, n: int) -> "Rays":
        return Rays(self.origins[:n], self.directions[:n], self.t_max[:n])


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def camera_rays(lo, hi, width: int, height: int, fov_deg: float = 40.0,
                direction=(0.0, 0.75, 1.0), margin: float = 0.6) -> Rays:
    """One ray through each pixel centre of a pinhole camera looking at the centre of the box
    [lo, hi] from `direction`. margin 1 fits the box's bounding sphere in the view, which leaves
    most pixels empty; 0.6 is a closer view where most rays hit (about 60 % on the bunny and
    the terrains), as in a rendered frame."""
    from renderer.scene.framing import frame_camera

    position, look_at = frame_camera(np.stack([lo, hi]), fov_deg, width / height, direction, margin=margin)
    eye = np.asarray(position, np.float64)
    forward = _unit(np.asarray(look_at, np.float64) - eye)
    right = _unit(np.cross(forward, (0.0, 1.0, 0.0)))
    up = np.cross(right, forward)
    tan_v = math.tan(math.radians(fov_deg) / 2.0)
    tan_h = tan_v * width / height
    xs = ((np.arange(width) + 0.5) / width * 2.0 - 1.0) * tan_h
    ys = (1.0 - (np.arange(height) + 0.5) / height * 2.0) * tan_v
    gx, gy = np.meshgrid(xs, ys)  # row-major: scanlines, the order a renderer fires them
    d = _unit(forward + gx[..., None] * right + gy[..., None] * up).reshape(-1, 3)
    o = np.broadcast_to(eye, d.shape)
    return Rays(np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32),
                np.full(len(d), FAR, np.float32))


def random_rays(lo, hi, n: int, seed: int) -> tuple[Rays, Rays]:
    """Incoherent rays: origins uniform on a sphere of 1.5x the box's bounding radius around its
    centre, aimed at uniform random points in the box. Returns (closest-hit rays with t_max = FAR,
    the same rays as shadow segments ending at their target points)."""
    rng = np.random.default_rng(seed)
    lo = np.asarray(lo, np.float64)
    hi = np.asarray(hi, np.float64)
    centre = 0.5 * (lo + hi)
    radius = 1.5 * max(0.5 * float(np.linalg.norm(hi - lo)), 1e-6)
    origins = centre + radius * _unit(rng.normal(size=(n, 3)))
    targets = rng.uniform(lo, hi, size=(n, 3))
    delta = targets - origins
    length = np.linalg.norm(delta, axis=1)
    o = np.ascontiguousarray(origins, np.float32)
    d = np.ascontiguousarray(delta / length[:, None], np.float32)
    return (Rays(o, d, np.full(n, FAR, np.float32)), Rays(o, d, length.astype(np.float32)))


# --- Lantern -----------------------------------------------------------------------------------

def _tracer_class():
    """The kernels, defined on first use (Taichi stays untouched at import time)."""
    import taichi as ti

    from renderer.geometry.interface import Ray

    @ti.data_oriented
    class Tracer:
        """Fires ndarrays of rays at one MeshGeometry."""

        def __init__(self, geometry):
            self.geometry = geometry

        @ti.kernel
        def _closest(self, o: ti.types.ndarray(), d: ti.types.ndarray(), t_max: ti.types.ndarray(),
                     out_t: ti.types.ndarray(), out_stats: ti.types.ndarray()):
            for i in range(o.shape[0]):
                ray = Ray(o=ti.math.vec3(o[i, 0], o[i, 1], o[i, 2]), d=ti.math.vec3(d[i, 0], d[i, 1], d[i, 2]),
                          cone_width=0.0, cone_spread=0.0)
                hit = self.geometry.intersect(ray, t_max[i])
                out_t[i] = hit.t if hit.hit == 1 else -1.0
                out_stats[i, 0] = hit.work
                out_stats[i, 1] = hit.tests

        @ti.kernel
        def _occluded(self, o: ti.types.ndarray(), d: ti.types.ndarray(), t_max: ti.types.ndarray(),
                      out: ti.types.ndarray()):
            for i in range(o.shape[0]):
                ray = Ray(o=ti.math.vec3(o[i, 0], o[i, 1], o[i, 2]), d=ti.math.vec3(d[i, 0], d[i, 1], d[i, 2]),
                          cone_width=0.0, cone_spread=0.0)
                out[i] = 1 if self.geometry.occluded(ray, t_max[i]) else 0

        def closest(self, rays: Rays, out_t: np.ndarray, out_stats: np.ndarray) -> None:
            self._closest(rays.origins, rays.directions, rays.t_max, out_t, out_stats)
            ti.sync()

        def occluded(self, rays: Rays, out: np.ndarray) -> None:
            self._occluded(rays.origins, rays.directions, rays.t_max, out)
            ti.sync()

    return Tracer


_TRACER = None


def tracer_for(geometry):
    global _TRACER
    if _TRACER is None:
        _TRACER = _tracer_class()
    return _TRACER(geometry)


class ClosestCall:
    """One configuration on one ray set: output buffers plus a timed callable."""

    def __init__(self, tracer, rays: Rays):
        self.tracer = tracer
        self.rays = rays
        self.t = np.zeros(len(rays), np.float32)
        self.stats = np.zeros((len(rays), 2), np.int32)

    def __call__(self):
        self.tracer.closest(self.rays, self.t, self.stats)

    def summary(self, timing) -> dict:
        n = len(self.rays)
        return {"rays": n, "mrays_per_s": n / timing.median / 1e6, "mrays_per_s_best": n / min(timing.times) / 1e6,
                "timing": timing.as_dict(), "nodes_per_ray": float(self.stats[:, 0].mean()),
                "tests_per_ray": float(self.stats[:, 1].mean()),
                "hit_fraction": float((self.t >= 0).mean())}


class OccludedCall:
    def __init__(self, tracer, rays: Rays):
        self.tracer = tracer
        self.rays = rays
        self.out = np.zeros(len(rays), np.int32)

    def __call__(self):
        self.tracer.occluded(self.rays, self.out)


def mesh_data(tris: np.ndarray):
    from renderer.geometry.mesh_data import MeshData

    return MeshData(tri_vertices=np.ascontiguousarray(tris, np.float32),
                    tri_material=np.zeros(len(tris), np.int32))


def _builder_threads() -> int | None:
    """Threads build_bvh will use right now (it decides by the load average), if it says."""
    from renderer.geometry import bvh_build

    fn = getattr(bvh_build, "_default_threads", None)
    return int(fn()) if fn is not None else None


def build_stats(bvh) -> dict:
    from renderer.geometry.bvh_build import sah_cost

    leaves = bvh.node_count > 0
    return {"sah_cost": sah_cost(bvh), "nodes": bvh.num_nodes, "leaves": int(leaves.sum()),
            "mean_leaf_size": float(bvh.node_count[leaves].mean()), "largest_leaf": int(bvh.node_count.max()),
            "depth": bvh.depth()}


def timed_builds(lo, hi, centroids, strategy: str, leaf: int, runs: int):
    """(last tree, Timing) of `runs` build_bvh calls (no warm-up: a build compiles nothing)."""
    from renderer.geometry.bvh_build import build_bvh

    out = {}

    def build():
        out["bvh"] = build_bvh(lo, hi, centroids, strategy=strategy, max_leaf_size=leaf)

    timing = time_call(build, runs=runs, warmup=0)
    return out["bvh"], timing


def bytes_of(geometry, triangles: int) -> dict:
    b = geometry.device_bytes()
    total = int(b["bvh"]) + int(b["triangles"])
    per = total / triangles
    return {"bvh": int(b["bvh"]), "triangles": int(b["triangles"]), "total": total,
            "per_triangle": per, "bvh_per_triangle": int(b["bvh"]) / triangles,
            "target_passed": per <= BYTES_PER_TRIANGLE_TARGET}


# --- Embree ------------------------------------------------------------------------------------

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
        n = len(self.rays)
        return {"rays": n, "mrays_per_s": n / timing.median / 1e6, "mrays_per_s_best": n / min(timing.times) / 1e6,
                "timing": timing.as_dict(), "hit_fraction": float(self.hit.mean())}


class EmbreeOccludedCall:
    def __init__(self, embree: EmbreeMesh, rays: Rays):
        self.embree = embree
        self.rays = rays
        self.out = np.zeros(len(rays), np.int32)

    def __call__(self):
        self.embree.occluded(self.rays, self.out)


def _compare(lantern_t: np.ndarray, embree_t: np.ndarray, embree_hit: np.ndarray, rtol: float):
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
    agree, l_hit, both, close, rel = _compare(lantern_t, embree_t, embree_hit, rtol)
    n = max(1, lantern_t.shape[0])
    return {"fraction": float(agree.sum() / n), "rays": int(lantern_t.shape[0]), "disagreeing": int((~agree).sum()),
            "lantern_only_hits": int((l_hit & ~embree_hit).sum()),
            "embree_only_hits": int((~l_hit & embree_hit).sum()),
            "distance_mismatches": int((both & ~close).sum()),
            "max_relative_difference": float(rel.max()) if rel.size else 0.0}


# --- one mesh ----------------------------------------------------------------------------------

def _config_name(strategy: str, traversal: str, test: str) -> str:
    return f"{strategy}/{traversal}/{test}"


def measure_mesh(name: str, tris: np.ndarray, config: BvhBenchConfig, embree=None, pool=None,
                 log=print) -> dict:
    """Build, trace and compare one mesh. `embree` is load_embree()'s (module, class, version) or
    None; `pool` a thread pool for Embree's rays. Taichi must be initialised. Returns the mesh's
    part of the report (JSON-ready after common.write_json's conversion)."""
    import taichi as ti

    from renderer.geometry.mesh_geometry import MeshGeometry

    n_tris = int(len(tris))
    large = n_tris >= SAH_BUILD_TARGET_MIN_TRIANGLES
    build_runs = config.build_runs_large if large else config.build_runs
    data = mesh_data(tris)
    t0 = time.perf_counter()
    lo, hi = data.bounds()
    centroids = 0.5 * (lo + hi)
    bounds_s = time.perf_counter() - t0
    box_lo, box_hi = lo.min(axis=0), hi.max(axis=0)
    result = {"name": name, "triangles": n_tris, "bounds": [box_lo, box_hi], "bounds_s": bounds_s,
              "build_runs": build_runs, "builds": [], "configs": []}
    threads = int(ti.lang.impl.current_cfg().cpu_max_num_threads)

    # 1. builds, and a device copy of each tree for every traversal x triangle test
    geometries = {}
    for strategy in config.strategies:
        builder_threads = _builder_threads()
        bvh, timing = timed_builds(lo, hi, centroids, strategy, DEFAULT_LEAF, build_runs)
        row = {"strategy": strategy, "max_leaf_size": DEFAULT_LEAF, "seconds": timing.median,
               "timing": timing.as_dict(), "triangles_per_s": n_tris / timing.median,
               "builder_threads": builder_threads, **build_stats(bvh)}
        for traversal in config.traversals:
            for test in config.triangle_tests:
                t0 = time.perf_counter()
                geometries[(strategy, traversal, test)] = MeshGeometry(data, bvh, traversal, test)
                row.setdefault("upload_s", time.perf_counter() - t0)
        row["device_bytes"] = bytes_of(next(g for k, g in geometries.items() if k[0] == strategy), n_tris)
        result["builds"].append(row)
        log(f"  {name}: {strategy} build {timing.median:.3f} s, SAH cost {row['sah_cost']:.2f}, "
            f"{row['device_bytes']['per_triangle']:.1f} bytes/triangle")

    # 2. rays
    cw, chh = config.camera
    rays = {"coherent": camera_rays(box_lo, box_hi, cw, chh)}
    rays["incoherent"], shadow = random_rays(box_lo, box_hi, config.incoherent_rays, config.seed)
    result["rays"] = {"coherent": {"count": len(rays["coherent"]), "camera": [cw, chh]},
                      "incoherent": {"count": len(rays["incoherent"])}}

    # Embree: scene build (commit) and its calls
    emb = None
    if embree is not None and embree[0] is not None:
        try:
            emb = EmbreeMesh(embree[0], embree[1], tris, threads, pool)
            probe = rays["incoherent"].head(64)  # fail here, not in the middle of the timing
            emb.closest(probe, np.zeros(len(probe), np.float32), np.zeros(len(probe), np.int32))
            result["embree"] = {"available": True, "build_s": emb.build_s, "upload_s": emb.upload_s,
                                "robust": emb.robust, "trace_threads": threads}
        except Exception as e:  # noqa: BLE001 - never let the optional column crash the run
            log(f"  note: Embree failed on {name} ({type(e).__name__}: {e}); its column is skipped")
            emb = None
    if emb is None:
        result["embree"] = {"available": False}

    # compile every configuration on a handful of rays, then time all round-robin
    tracers = {key: tracer_for(g) for key, g in geometries.items()}
    calls, compile_s = {}, {}
    for key, tracer in tracers.items():
        few = ClosestCall(tracer, rays["incoherent"].head(64))
        t0 = time.perf_counter()
        few()
        compile_s[key] = time.perf_counter() - t0
        for kind, r in rays.items():
            calls[(key, kind)] = ClosestCall(tracer, r)
    emb_calls = {}
    if emb is not None:
        for kind, r in rays.items():
            emb_calls[kind] = EmbreeClosestCall(emb, r)
    named = {f"{_config_name(*key)}:{kind}": c for (key, kind), c in calls.items()}
    named.update({f"embree:{kind}": c for kind, c in emb_calls.items()})
    log(f"  {name}: timing {len(named)} ray calls x {config.trace_runs} runs ...")
    timings = time_interleaved(named, runs=config.trace_runs, warmup=1)

    for key in tracers:
        entry = {"strategy": key[0], "traversal": key[1], "triangle_test": key[2], "compile_s": compile_s[key]}
        for kind in rays:
            c = calls[(key, kind)]
            s = c.summary(timings[f"{_config_name(*key)}:{kind}"])
            if kind in emb_calls:
                e = emb_calls[kind]
                s["agreement"] = agreement(c.t, e.t, e.hit)
            entry[kind] = s
        result["configs"].append(entry)
    if emb is not None:
        for kind, e in emb_calls.items():
            result["embree"][kind] = e.summary(timings[f"embree:{kind}"])

    # the Renderer's configuration against Embree; the best configuration too
    default = next((c for c in result["configs"] if (c["strategy"], c["traversal"], c["triangle_test"]) == DEFAULT),
                   result["configs"][0])
    best = max(result["configs"], key=lambda c: c["incoherent"]["mrays_per_s"])
    result["default_config"] = _config_name(default["strategy"], default["traversal"], default["triangle_test"])
    result["best_incoherent_config"] = _config_name(best["strategy"], best["traversal"], best["triangle_test"])
    if emb is not None:
        ratios = {}
        for kind in rays:
            e_rate = result["embree"][kind]["mrays_per_s"]
            ratios[kind] = {"default": default[kind]["mrays_per_s"] / e_rate,
                            "best": max(c[kind]["mrays_per_s"] for c in result["configs"]) / e_rate,
                            # from each side's fastest run: less sensitive to other load on the machine
                            "default_fastest_runs": (default[kind]["mrays_per_s_best"]
                                                     / result["embree"][kind]["mrays_per_s_best"])}
        result["ratio_to_embree"] = ratios
        result["embree_target_passed"] = ratios["incoherent"]["default"] >= EMBREE_RATIO_TARGET
        per_kind = {}
        for kind in rays:
            e = emb_calls[kind]
            ok = np.ones(len(rays[kind]), bool)
            for key in tracers:
                ok &= _compare(calls[(key, kind)].t, e.t, e.hit, AGREEMENT_RTOL)[0]
            per_kind[kind] = float(ok.mean())
        result["agreement_all_configs"] = per_kind

    # any-hit (shadow) segments on the Renderer's configuration
    if config.shadow_rays:
        key = (default["strategy"], default["traversal"], default["triangle_test"])
        tracer = tracers[key]
        occ = OccludedCall(tracer, shadow)
        occ.tracer.occluded(shadow.head(64), np.zeros(64, np.int32))  # compile
        seg_closest = ClosestCall(tracer, shadow)
        shadow_calls = {"lantern:occluded": occ, "lantern:closest": seg_closest}
        e_occ = None
        if emb is not None:
            e_occ = EmbreeOccludedCall(emb, shadow)
            shadow_calls["embree:occluded"] = e_occ
        st = time_interleaved(shadow_calls, runs=config.trace_runs, warmup=1)
        n = len(shadow)
        sh = {"config": _config_name(*key), "rays": n,
              "occluded_mrays_per_s": n / st["lantern:occluded"].median / 1e6,
              "closest_mrays_per_s": n / st["lantern:closest"].median / 1e6,
              "occluded_fraction": float(occ.out.mean()),
              "closest_hit_fraction": float((seg_closest.t >= 0).mean()),
              "closest_nodes_per_ray": float(seg_closest.stats[:, 0].mean()),
              "timing": {k: v.as_dict() for k, v in st.items()}}
        # a segment is occluded exactly when its closest hit lies inside it
        sh["consistent_with_closest"] = float((occ.out.astype(bool) == (seg_closest.t >= 0)).mean())
        if e_occ is not None:
            sh["embree_occluded_mrays_per_s"] = n / st["embree:occluded"].median / 1e6
            sh["embree_occluded_fraction"] = float(e_occ.out.mean())
            sh["agreement_with_embree"] = float((occ.out == e_occ.out).mean())
        result["shadow"] = sh
    return result


def leaf_size_sweep(name: str, tris: np.ndarray, config: BvhBenchConfig, log=print) -> dict:
    """SAH builds with each max_leaf_size: build time, bytes/triangle, incoherent Mrays/s."""
    from renderer.geometry.mesh_geometry import MeshGeometry

    n_tris = int(len(tris))
    data = mesh_data(tris)
    lo, hi = data.bounds()
    centroids = 0.5 * (lo + hi)
    rays, _ = random_rays(lo.min(axis=0), hi.max(axis=0), config.incoherent_rays, config.seed)
    runs = config.build_runs_large if n_tris >= SAH_BUILD_TARGET_MIN_TRIANGLES else config.build_runs
    rows, calls = [], {}
    for leaf in config.leaf_sizes:
        bvh, timing = timed_builds(lo, hi, centroids, "sah", leaf, runs)
        geometry = MeshGeometry(data, bvh, "stack", "watertight")
        call = ClosestCall(tracer_for(geometry), rays)
        t0 = time.perf_counter()
        ClosestCall(call.tracer, rays.head(64))()
        compile_s = time.perf_counter() - t0
        calls[leaf] = call
        rows.append({"max_leaf_size": leaf, "build_s": timing.median, "timing": timing.as_dict(),
                     "compile_s": compile_s, "device_bytes": bytes_of(geometry, n_tris), **build_stats(bvh)})
    log(f"  leaf sizes on {name}: timing {len(calls)} ray calls x {config.trace_runs} runs ...")
    timings = time_interleaved({str(k): c for k, c in calls.items()}, runs=config.trace_runs, warmup=1)
    for row in rows:
        c = calls[row["max_leaf_size"]]
        row["incoherent"] = c.summary(timings[str(row["max_leaf_size"])])
    best = max(rows, key=lambda r: r["incoherent"]["mrays_per_s"])
    top = best["incoherent"]["mrays_per_s"]
    near = [r["max_leaf_size"] for r in rows if r["incoherent"]["mrays_per_s"] >= (1.0 - LEAF_TIE) * top]
    return {"mesh": name, "triangles": n_tris, "config": "sah/stack/watertight", "rays": len(rays),
            "rows": rows, "best_max_leaf_size": best["max_leaf_size"], "within_tie_of_best": near,
            "tie_fraction": LEAF_TIE, "renderer_default": DEFAULT_LEAF}


# --- report --------------------------------------------------------------------------------------

def _pct(x) -> str:
    return "-" if x is None else f"{100 * x:.3f}%"


def _print_discrepancies(m: dict) -> None:
    """One line per distinct disagreement with Embree, naming the configurations that show it."""
    groups = {}
    for c in m["configs"]:
        for kind in ("coherent", "incoherent"):
            a = c[kind].get("agreement")
            if a and a["disagreeing"]:
                key = (kind, a["disagreeing"], a["lantern_only_hits"], a["embree_only_hits"],
                       a["distance_mismatches"], f"{a['max_relative_difference']:.2g}", a["rays"])
                groups.setdefault(key, []).append(c)
    n_per_test = len({(c["strategy"], c["traversal"]) for c in m["configs"]})
    for (kind, bad, l_only, e_only, far, rel, rays), configs in groups.items():
        tests = {c["triangle_test"] for c in configs}
        if len(tests) == 1 and len(configs) == n_per_test and n_per_test > 1:
            who = f"all {len(configs)} {tests.pop()} configurations alike"
        else:
            who = ", ".join(_config_name(c["strategy"], c["traversal"], c["triangle_test"]) for c in configs)
        print(f"    differs from Embree on {kind} rays: {bad} of {rays:,} (hit only by Lantern {l_only}, only by "
              f"Embree {e_only}, distance beyond {AGREEMENT_RTOL:g} {far}; largest relative distance difference "
              f"{rel}): {who}")


def print_report(report: dict) -> None:
    meshes = report["meshes"]
    th = report["threads"]
    print(f"Threads: Taichi CPU kernels {th['taichi']}; BVH builder (numpy) {th['bvh_builder']}; "
          f"Embree rays {th['embree_trace']} (Python threads over chunks), Embree build: its own pool over "
          f"{th['embree_build']} cores.  Embree: "
          f"{report['embree']['version'] if report['embree']['available'] else 'n/a'}")
    la = report["load_average"]
    print(f"Load average (1, 5, 15 min) before {la['before']}, after {la['after']}, on {os.cpu_count()} cores: "
          f"timings are only as quiet as the machine.")
    print()
    rows = []
    for m in meshes:
        for b in m["builds"]:
            db = b["device_bytes"]
            rows.append([m["name"], m["triangles"], b["strategy"], b["seconds"], b["triangles_per_s"] / 1e6,
                         b["sah_cost"], b["nodes"], b["depth"], b["mean_leaf_size"], db["bvh_per_triangle"],
                         db["per_triangle"], verdict(db["target_passed"])])
        if m["embree"].get("available"):
            rows.append([m["name"], m["triangles"], "embree", m["embree"]["build_s"],
                         m["triangles"] / m["embree"]["build_s"] / 1e6, "-", "-", "-", "-", "-", "-", ""])
    print_table(["mesh", "tris", "strategy", "build s", "Mtris/s", "SAH cost", "nodes", "depth", "leaf avg",
                 "B/tri bvh", "B/tri all", f"<= {BYTES_PER_TRIANGLE_TARGET:g} B"], rows,
                title=f"BVH build (median of {report['config']['build_runs']} builds, "
                      f"{report['config']['build_runs_large']} for 1M; max_leaf_size {DEFAULT_LEAF}; boxes and "
                      f"centroids prepared beforehand; embree = scene commit)")
    for m in meshes:
        print(f"  {m['name']}: per-triangle boxes + centroids {m['bounds_s']:.3f} s (not in the build times)")
    print()

    for m in meshes:
        rows = []
        for c in m["configs"]:
            co, inc = c["coherent"], c["incoherent"]
            rows.append([_config_name(c["strategy"], c["traversal"], c["triangle_test"]), c["compile_s"],
                         co["mrays_per_s"], co["nodes_per_ray"], co["tests_per_ray"],
                         _pct(co.get("agreement", {}).get("fraction")),
                         inc["mrays_per_s"], inc["nodes_per_ray"], inc["tests_per_ray"],
                         _pct(inc.get("agreement", {}).get("fraction"))])
        e = m["embree"]
        if e.get("available"):
            rows.append(["embree", "-", e["coherent"]["mrays_per_s"], "-", "-", "",
                         e["incoherent"]["mrays_per_s"], "-", "-", ""])
        r = m["rays"]
        hits = {kind: m["configs"][0][kind]["hit_fraction"] for kind in ("coherent", "incoherent")}
        print_table(["config", "1st call s", "coh Mray/s", "nodes", "tests", "=embree",
                     "incoh Mray/s", "nodes", "tests", "=embree"], rows,
                    title=f"Closest-hit traversal, {m['name']} ({m['triangles']:,} triangles): coherent = "
                          f"{r['coherent']['camera'][0]}x{r['coherent']['camera'][1]} camera rays "
                          f"({hits['coherent']:.0%} hit), incoherent = {r['incoherent']['count']:,} random rays "
                          f"({hits['incoherent']:.0%} hit); nodes/tests = mean per ray; =embree = rays agreeing "
                          f"with Embree (same miss, or t within {AGREEMENT_RTOL:g} relative); 1st call = compile "
                          f"(or load from Taichi's offline cache) + 64 rays")
        if e.get("available"):
            ratio = m["ratio_to_embree"]
            print(f"  Lantern/Embree on {m['name']}: incoherent {ratio['incoherent']['default']:.3f}x "
                  f"({m['default_config']}; fastest runs {ratio['incoherent']['default_fastest_runs']:.3f}x), "
                  f"best config {ratio['incoherent']['best']:.3f}x ({m['best_incoherent_config']}); "
                  f"coherent {ratio['coherent']['default']:.3f}x, best config {ratio['coherent']['best']:.3f}x")
            agr = m["agreement_all_configs"]
            print(f"  rays on which all {len(m['configs'])} configurations agree with Embree: coherent "
                  f"{_pct(agr['coherent'])}, incoherent {_pct(agr['incoherent'])}")
            _print_discrepancies(m)
        print()

    shadow = [m for m in meshes if "shadow" in m]
    if shadow:
        rows = []
        for m in shadow:
            s = m["shadow"]
            rows.append([m["name"], s["config"], s["occluded_mrays_per_s"], s["closest_mrays_per_s"],
                         s["occluded_mrays_per_s"] / s["closest_mrays_per_s"], _pct(s["occluded_fraction"]),
                         _pct(s["consistent_with_closest"]), s.get("embree_occluded_mrays_per_s", "-"),
                         _pct(s.get("agreement_with_embree"))])
        print_table(["mesh", "config", "any-hit Mray/s", "closest Mray/s", "speed-up", "occluded",
                     "=closest", "embree any Mray/s", "=embree"], rows,
                    title="Shadow rays (the incoherent rays as segments ending at their random targets): any-hit "
                          "(occluded) vs closest-hit on the same segments")

    leaf = report.get("leaf_size")
    if leaf:
        rows = []
        for r in leaf["rows"]:
            inc = r["incoherent"]
            rows.append([("*" if r["max_leaf_size"] == DEFAULT_LEAF else "") + str(r["max_leaf_size"]), r["build_s"],
                         r["nodes"], r["mean_leaf_size"], r["largest_leaf"], r["depth"], r["sah_cost"],
                         r["device_bytes"]["per_triangle"], inc["mrays_per_s"], inc["nodes_per_ray"],
                         inc["tests_per_ray"]])
        print_table(["max leaf", "build s", "nodes", "leaf avg", "largest", "depth", "SAH cost", "B/tri",
                     "incoh Mray/s", "nodes", "tests"], rows,
                    title=f"Leaf size, SAH on {leaf['mesh']} ({leaf['triangles']:,} triangles), "
                          f"{leaf['config']}, {leaf['rays']:,} incoherent rays (* = Renderer default)")
        print(f"  best max_leaf_size by incoherent rays/s: {leaf['best_max_leaf_size']} "
              f"(Renderer default {leaf['renderer_default']}); within {leaf['tie_fraction']:.0%} of the best: "
              f"{', '.join(str(v) for v in leaf['within_tie_of_best'])}")
        print()

    t = report["targets"]
    print("Targets:")
    for m in meshes:
        b = next((b for b in m["builds"] if b["strategy"] == "sah"), None)
        if b is not None:
            db = b["device_bytes"]
            print(f"  bytes/triangle on the device (sah, leaf {DEFAULT_LEAF}), {m['name']}: {db['per_triangle']:.1f} "
                  f"(BVH {db['bvh_per_triangle']:.1f} + triangles {db['triangles'] / m['triangles']:.1f}) "
                  f"<= {BYTES_PER_TRIANGLE_TARGET:g}: {verdict(db['target_passed'])}")
    sb = t.get("sah_build_1m")
    if sb:
        print(f"  SAH build of {sb['triangles']:,} triangles: {sb['seconds']:.3f} s <= {SAH_BUILD_TARGET_S:g} s: "
              f"{verdict(sb['passed'])}")
    else:
        print("  SAH build of 1M triangles: not measured (no mesh that large)")
    if report["embree"]["available"]:
        for m in meshes:
            if "ratio_to_embree" in m:
                r = m["ratio_to_embree"]["incoherent"]["default"]
                print(f"  incoherent closest-hit vs Embree, {m['name']} ({m['default_config']}): {r:.3f}x "
                      f">= {EMBREE_RATIO_TARGET:g}x: {verdict(r >= EMBREE_RATIO_TARGET)}")
    else:
        print(f"  incoherent closest-hit vs Embree: not measured ({report['embree']['note']})")
    print(flush=True)


def write_plots(report: dict, out_dir: Path) -> list[Path]:
    plt = pyplot()
    written = []
    meshes = report["meshes"]
    strategies = [b["strategy"] for b in meshes[0]["builds"]] if meshes else []

    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    x = np.arange(len(meshes))
    width = 0.8 / (len(strategies) + 1)
    for i, s in enumerate(strategies):
        rows = [next(b for b in m["builds"] if b["strategy"] == s) for m in meshes]
        axes[0].bar(x + i * width, [r["seconds"] for r in rows], width, label=s)
        axes[1].bar(x + i * width, [r["sah_cost"] for r in rows], width, label=s)
        axes[2].bar(x + i * width, [r["device_bytes"]["per_triangle"] for r in rows], width, label=s)
    if report["embree"]["available"]:
        axes[0].bar(x + len(strategies) * width, [m["embree"].get("build_s", 0.0) for m in meshes], width,
                    label="embree (commit)", color="grey")
    axes[0].axhline(SAH_BUILD_TARGET_S, color="red", ls="--", lw=1, label="target: 1M SAH <= 2 s")
    axes[0].set_yscale("log")
    axes[0].set_ylabel("build seconds (median)")
    axes[1].set_ylabel("SAH cost (C_trav 1, C_isect 2)")
    axes[2].axhline(BYTES_PER_TRIANGLE_TARGET, color="red", ls="--", lw=1, label="target <= 64")
    axes[2].set_ylabel("device bytes per triangle (BVH + triangles)")
    axes[2].set_ylim(0, 1.4 * BYTES_PER_TRIANGLE_TARGET)
    for ax in axes:
        ax.set_xticks(x + width * len(strategies) / 2)
        ax.set_xticklabels([f"{m['name']}\n{m['triangles']:,}" for m in meshes], fontsize=8)
        ax.grid(True, axis="y", alpha=0.3)
        ax.legend(fontsize=7, ncol=2 if ax is axes[2] else 1)
    axes[0].set_title("BVH build time")
    axes[1].set_title("tree quality")
    axes[2].set_title("memory")
    written.append(save_figure(fig, out_dir / "bench_bvh_build.png"))

    if meshes:
        fig, axes = plt.subplots(2, len(meshes), figsize=(5 * len(meshes), 8), squeeze=False)
        for col, m in enumerate(meshes):
            for row, kind in enumerate(("coherent", "incoherent")):
                ax = axes[row, col]
                labels = [_config_name(c["strategy"], c["traversal"], c["triangle_test"]) for c in m["configs"]]
                values = [c[kind]["mrays_per_s"] for c in m["configs"]]
                colors = ["C0" if lab == m["default_config"] else "C1" for lab in labels]
                if m["embree"].get("available"):
                    labels.append("embree")
                    values.append(m["embree"][kind]["mrays_per_s"])
                    colors.append("grey")
                y = np.arange(len(labels))
                ax.barh(y, values, color=colors)
                ax.set_yticks(y)
                ax.set_yticklabels(labels, fontsize=7)
                ax.invert_yaxis()
                if kind == "incoherent" and m["embree"].get("available"):
                    ax.axvline(EMBREE_RATIO_TARGET * m["embree"][kind]["mrays_per_s"], color="red", ls="--", lw=1,
                               label=f"{EMBREE_RATIO_TARGET:g}x Embree")
                    ax.legend(fontsize=7)
                ax.set_xlabel("Mrays/s (closest hit)")
                ax.set_title(f"{m['name']}: {kind} rays", fontsize=9)
                ax.grid(True, axis="x", alpha=0.3)
        written.append(save_figure(fig, out_dir / "bench_bvh_trace.png"))

    leaf = report.get("leaf_size")
    if leaf:
        fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
        sizes = [r["max_leaf_size"] for r in leaf["rows"]]
        axes[0].plot(sizes, [r["incoherent"]["mrays_per_s"] for r in leaf["rows"]], "o-")
        axes[0].set_ylabel("incoherent Mrays/s")
        axes[1].plot(sizes, [r["device_bytes"]["per_triangle"] for r in leaf["rows"]], "o-")
        axes[1].axhline(BYTES_PER_TRIANGLE_TARGET, color="red", ls="--", lw=1)
        axes[1].set_ylabel("device bytes per triangle")
        axes[2].plot(sizes, [r["build_s"] for r in leaf["rows"]], "o-")
        axes[2].set_ylabel("SAH build seconds")
        for ax in axes:
            ax.set_xscale("log", base=2)
            ax.set_xticks(sizes)
            ax.set_xticklabels([str(s) for s in sizes])
            ax.set_xlabel("max_leaf_size")
            ax.grid(True, alpha=0.3)
        fig.suptitle(f"SAH leaf size on {leaf['mesh']}")
        written.append(save_figure(fig, out_dir / "bench_bvh_leaf_size.png"))
    return written


# --- entry -------------------------------------------------------------------------------------

def run(quick: bool = False, out_dir: Path = Path("reports"), config: BvhBenchConfig | None = None) -> int:
    """Measure every mesh of the configuration; print tables, write JSON and plots."""
    import taichi as ti

    config = config or (QUICK if quick else FULL)
    out_dir = Path(out_dir)
    t_start = time.perf_counter()
    arch = speed_runtime()
    threads = int(ti.lang.impl.current_cfg().cpu_max_num_threads)
    load_before = load_average()

    embree = (None, None, "disabled in the configuration")
    if config.embree:
        embree = load_embree()
        if embree[0] is None:
            print(f"note: the embreex package is not importable ({embree[2]}); the Embree columns are skipped. "
                  f"Install it with `pip install embreex` (or the project's `bench` extra).", flush=True)
    embree_info = {"available": embree[0] is not None}
    if embree[0] is not None:
        embree_info["version"] = embree[2]
    else:
        embree_info["note"] = embree[2]

    pool = ThreadPoolExecutor(max_workers=threads) if embree[0] is not None else None
    meshes, leaf = [], None
    try:
        for spec in config.meshes:
            t0 = time.perf_counter()
            tris = spec.load()
            print(f"{spec.name}: {len(tris):,} triangles (loaded in {time.perf_counter() - t0:.2f} s)", flush=True)
            meshes.append(measure_mesh(spec.name, tris, config, embree if embree[0] is not None else None, pool))
            if spec.name == config.leaf_mesh and config.leaf_sizes:
                leaf = leaf_size_sweep(spec.name, tris, config)
            del tris
    finally:
        if pool is not None:
            pool.shutdown()

    big = [m for m in meshes if m["triangles"] >= SAH_BUILD_TARGET_MIN_TRIANGLES]
    targets = {"bytes_per_triangle": BYTES_PER_TRIANGLE_TARGET, "sah_build_seconds": SAH_BUILD_TARGET_S,
               "embree_ratio": EMBREE_RATIO_TARGET, "agreement_rtol": AGREEMENT_RTOL}
    if big:
        m = big[-1]
        b = next((b for b in m["builds"] if b["strategy"] == "sah"), None)
        if b is not None:
            targets["sah_build_1m"] = {"mesh": m["name"], "triangles": m["triangles"], "seconds": b["seconds"],
                                       "passed": b["seconds"] <= SAH_BUILD_TARGET_S}
    targets["bytes_per_triangle_passed"] = {
        m["name"]: b["device_bytes"]["target_passed"] for m in meshes for b in m["builds"] if b["strategy"] == "sah"}
    if embree_info["available"]:
        targets["embree_ratio_passed"] = {m["name"]: m.get("embree_target_passed") for m in meshes}

    report = {
        "benchmark": "bvh",
        "quick": quick,
        "arch": arch,
        "machine": machine_info(),
        "threads": {"taichi": threads, "bvh_builder": sorted({b["builder_threads"] for m in meshes
                                                              for b in m["builds"] if b["builder_threads"]}),
                    "embree_trace": threads if embree_info["available"] else None,
                    "embree_build": os.cpu_count()},
        "embree": embree_info,
        "config": {**asdict(config), "meshes": [asdict(s) for s in config.meshes]},
        "load_average": {"before": load_before, "after": load_average()},
        "targets": targets,
        "notes": ("Build times are build_bvh alone (per-primitive boxes and centroids prepared beforehand, "
                  "bounds_s). Device bytes = MeshGeometry.device_bytes() (BVH nodes + primitive index, triangle "
                  "vertices). Trace: ndarray rays, one kernel launch per call followed by ti.sync(); every "
                  "configuration compiled before timing; timed calls round-robin over all configurations of a "
                  "mesh and Embree; Mrays/s from the median. Embree: embreex's rtcIntersect1/rtcOccluded1 loop "
                  "(robust scene flag), rays cut into chunks over as many Python threads as Taichi's CPU "
                  "threads. Agreement: both miss, or both hit with |t_lantern - t_embree| <= 1e-4 t_embree. "
                  "Shadow rays: the incoherent rays as segments ending at their random target points."),
        "meshes": meshes,
        "leaf_size": leaf,
    }
    print()
    print_report(report)
    plots = write_plots(report, out_dir)
    report["plots"] = [p.name for p in plots]
    report["total_seconds"] = time.perf_counter() - t_start
    path = write_json(out_dir / "bench_bvh.json", report)
    print(f"wrote {path} and {', '.join(p.name for p in plots)} in {out_dir}  "
          f"(total {report['total_seconds']:.0f} s)", flush=True)
    return 0

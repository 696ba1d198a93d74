"""The BVH benchmark's measurements: its meshes and configuration, the builds (time, SAH cost,
device bytes), closest-hit and shadow rays per split strategy x traversal x triangle test, Embree
on the same rays, and the leaf-size sweep. `renderer.bench.bvh` runs them and reports."""
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import taichi as ti

from renderer.bench import embree_side
from renderer.bench.common import time_call, time_interleaved
from renderer.bench.ray_batch import RayBatch
from renderer.bench.rays import Rays, camera_rays, random_rays, ray_rates
from renderer.geometry import bvh_build, bvh_tree
from renderer.geometry.mesh_data import MeshData
from renderer.geometry.mesh_geometry import MeshGeometry
from renderer.renderer import MAX_LEAF_SIZE

ROOT = Path(__file__).resolve().parents[2]
BUNNY = ROOT / "assets" / "models" / "bunny.glb"

BYTES_PER_TRIANGLE_TARGET = 64.0  # BVH + triangle intersection data on the device, per triangle
SAH_BUILD_TARGET_S = 2.0  # SAH build of the 1M-triangle mesh
SAH_BUILD_TARGET_MIN_TRIANGLES = 1_000_000
EMBREE_RATIO_TARGET = 0.3  # Lantern / Embree incoherent closest-hit rays per second, every mesh
EMBREE_RATIO_TARGET_1M = 0.6  # the same on the mesh of a million triangles

STRATEGIES = ("sah", "midpoint", "equal_count")
# A traversal name with PACKETS appended uses the packet leaves (four slots tested at a time,
# triangles structure-of-arrays: renderer/geometry/triangle_packets.py) instead of the scalar ones.
PACKETS = "+packets"
TRAVERSALS = ("stack", "stackless", "wide4", "wide8", "stack" + PACKETS, "wide4" + PACKETS, "wide8" + PACKETS)
WIDE = "wide4"  # the 4-wide BVH's traversal, compared with the binary "stack" one on the same rays
TRIANGLE_TESTS = ("watertight", "moller")
DEFAULT = ("sah", "wide8+packets", "watertight")  # the Renderer's MeshOptions (traversal and leaves)
DEFAULT_LEAF = MAX_LEAF_SIZE["scalar"]  # the Renderer's max leaf size with scalar leaves (4)
PACKET_LEAF = MAX_LEAF_SIZE["packets"]  # and with packet leaves (8): the "+packets" configurations' trees
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


# --- Lantern -----------------------------------------------------------------------------------

class ClosestCall:
    """One configuration on one ray set: output buffers plus a timed callable."""

    def __init__(self, batch: RayBatch, rays: Rays):
        self.batch = batch
        self.rays = rays
        self.t = np.zeros(len(rays), np.float32)
        self.prim = np.zeros(len(rays), np.int32)
        self.stats = np.zeros((len(rays), 2), np.int32)

    def __call__(self):
        self.batch.closest(self.rays.origins, self.rays.directions, self.rays.t_max, self.t, self.prim, self.stats)

    def summary(self, timing) -> dict:
        return {**ray_rates(len(self.rays), timing), "nodes_per_ray": float(self.stats[:, 0].mean()),
                "tests_per_ray": float(self.stats[:, 1].mean()), "hit_fraction": float((self.t >= 0).mean())}


class OccludedCall:
    def __init__(self, batch: RayBatch, rays: Rays):
        self.batch = batch
        self.rays = rays
        self.out = np.zeros(len(rays), np.int32)

    def __call__(self):
        self.batch.occluded(self.rays.origins, self.rays.directions, self.rays.t_max, self.out)


def traversal_and_leaves(name: str) -> tuple[str, str]:
    """("wide4", "packets") for "wide4+packets", ("stack", "scalar") for "stack"."""
    return (name[: -len(PACKETS)], "packets") if name.endswith(PACKETS) else (name, "scalar")


def make_geometry(data: MeshData, bvh, traversal: str, test: str) -> MeshGeometry:
    base, leaves = traversal_and_leaves(traversal)
    return MeshGeometry(data, bvh, base, test, leaves=leaves)


def mesh_data(tris: np.ndarray) -> MeshData:
    return MeshData(tri_vertices=np.ascontiguousarray(tris, np.float32),
                    tri_material=np.zeros(len(tris), np.int32))


def _builder_threads() -> int | None:
    """Threads build_bvh will use right now (it decides by the load average), if it says."""
    fn = getattr(bvh_build, "_default_threads", None)
    return int(fn()) if fn is not None else None


def build_stats(bvh) -> dict:
    leaves = bvh.node_count > 0
    return {"sah_cost": bvh_tree.sah_cost(bvh), "nodes": bvh.num_nodes, "leaves": int(leaves.sum()),
            "mean_leaf_size": float(bvh.node_count[leaves].mean()), "largest_leaf": int(bvh.node_count.max()),
            "depth": bvh.depth()}


def timed_builds(lo, hi, centroids, strategy: str, leaf: int, runs: int):
    """(last tree, Timing) of `runs` build_bvh calls (no warm-up: a build compiles nothing)."""
    out = {}

    def build():
        out["bvh"] = bvh_build.build_bvh(lo, hi, centroids, strategy=strategy, max_leaf_size=leaf)

    timing = time_call(build, runs=runs, warmup=0)
    return out["bvh"], timing


def bytes_of(geometry, triangles: int) -> dict:
    b = geometry.device_bytes()
    total = int(b["bvh"]) + int(b["triangles"])
    per = total / triangles
    return {"bvh": int(b["bvh"]), "triangles": int(b["triangles"]), "total": total,
            "per_triangle": per, "bvh_per_triangle": int(b["bvh"]) / triangles,
            "target_passed": per <= BYTES_PER_TRIANGLE_TARGET}


# --- one mesh ----------------------------------------------------------------------------------

def config_name(strategy: str, traversal: str, test: str) -> str:
    return f"{strategy}/{traversal}/{test}"


def _build_all(name, data, n_tris, config, build_runs, log):
    """Each split strategy's tree (timed) and its device copy for every traversal x triangle test:
    (build rows, {(strategy, traversal, test): MeshGeometry})."""
    lo, hi = data.bounds()
    centroids = 0.5 * (lo + hi)
    rows, geometries = [], {}
    for strategy in config.strategies:
        builder_threads = _builder_threads()
        bvh, timing = timed_builds(lo, hi, centroids, strategy, DEFAULT_LEAF, build_runs)
        row = {"strategy": strategy, "max_leaf_size": DEFAULT_LEAF, "seconds": timing.median,
               "timing": timing.as_dict(), "triangles_per_s": n_tris / timing.median,
               "builder_threads": builder_threads, **build_stats(bvh)}
        packet_bvh = None
        for traversal in config.traversals:
            if traversal.endswith(PACKETS) and strategy != DEFAULT[0]:
                continue  # the leaf layouts are compared on the Renderer's split strategy only
            tree = bvh
            if traversal.endswith(PACKETS) and PACKET_LEAF != DEFAULT_LEAF:
                # packet leaves on the tree the Renderer builds for them (its leaf size for packets)
                if packet_bvh is None:
                    packet_bvh = bvh_build.build_bvh(lo, hi, centroids, strategy=strategy, max_leaf_size=PACKET_LEAF)
                    row["packet_tree"] = {"max_leaf_size": PACKET_LEAF, **build_stats(packet_bvh)}
                tree = packet_bvh
            for test in config.triangle_tests:
                t0 = time.perf_counter()
                geometries[(strategy, traversal, test)] = make_geometry(data, tree, traversal, test)
                row.setdefault("upload_s", time.perf_counter() - t0)
        own = {k[1]: g for k, g in geometries.items() if k[0] == strategy}
        binary = next((t for t in own if not t.startswith("wide") and not t.endswith(PACKETS)), None)
        row["device_bytes"] = bytes_of(own[binary] if binary else own[WIDE], n_tris)
        if WIDE in own:
            row["wide_device_bytes"] = bytes_of(own[WIDE], n_tris)
        if WIDE + PACKETS in own:
            row["wide_packets_device_bytes"] = bytes_of(own[WIDE + PACKETS], n_tris)
        row["device_bytes_by_traversal"] = {t: bytes_of(g, n_tris) for t, g in own.items()}
        rows.append(row)
        log(f"  {name}: {strategy} build {timing.median:.3f} s, SAH cost {row['sah_cost']:.2f}, "
            f"{row['device_bytes']['per_triangle']:.1f} bytes/triangle")
    return rows, geometries


def _embree_mesh(name, tris, embree, threads, pool, probe: Rays, log):
    """(EmbreeMesh or None, the report's "embree" entry): Embree's scene build (commit), tried on a
    few rays so that a failure shows here rather than in the middle of the timing."""
    if embree is None or embree[0] is None:
        return None, {"available": False}
    try:
        emb = embree_side.EmbreeMesh(embree[0], embree[1], tris, threads, pool)
        emb.closest(probe, np.zeros(len(probe), np.float32), np.zeros(len(probe), np.int32))
    except Exception as e:  # noqa: BLE001 - never let the optional column crash the run
        log(f"  note: Embree failed on {name} ({type(e).__name__}: {e}); its column is skipped")
        return None, {"available": False}
    return emb, {"available": True, "build_s": emb.build_s, "upload_s": emb.upload_s, "robust": emb.robust,
                 "trace_threads": threads}


def _compiled_batch(geometry, rays: Rays) -> tuple[RayBatch, float]:
    """The geometry's ray kernels, compiled (or loaded from the offline cache) by a first call on
    64 rays, and the seconds that call took."""
    batch = RayBatch(geometry)
    t0 = time.perf_counter()
    ClosestCall(batch, rays.head(64))()
    return batch, time.perf_counter() - t0


def _embree_ratios(result: dict, default: dict, kinds) -> dict:
    ratios = {}
    for kind in kinds:
        e_rate = result["embree"][kind]["mrays_per_s"]
        ratios[kind] = {"default": default[kind]["mrays_per_s"] / e_rate,
                        "best": max(c[kind]["mrays_per_s"] for c in result["configs"]) / e_rate,
                        # from each side's fastest run: less sensitive to other load on the machine
                        "default_fastest_runs": (default[kind]["mrays_per_s_best"]
                                                 / result["embree"][kind]["mrays_per_s_best"])}
    return ratios


def _shadow_rays(batch: RayBatch, key, shadow: Rays, emb, config, other=None) -> dict:
    """Any-hit (occluded) against closest-hit on the same segments, and Embree's any-hit; with
    `other` ((key, RayBatch) of the same strategy and test on the other tree: binary or wide),
    its any-hit too."""
    occ = OccludedCall(batch, shadow.head(64))
    occ()  # compile
    occ = OccludedCall(batch, shadow)
    seg_closest = ClosestCall(batch, shadow)
    shadow_calls = {"lantern:occluded": occ, "lantern:closest": seg_closest}
    other_occ = None
    if other is not None:
        OccludedCall(other[1], shadow.head(64))()  # compile
        other_occ = shadow_calls["lantern-other:occluded"] = OccludedCall(other[1], shadow)
    e_occ = None
    if emb is not None:
        e_occ = embree_side.EmbreeOccludedCall(emb, shadow)
        shadow_calls["embree:occluded"] = e_occ
    st = time_interleaved(shadow_calls, runs=config.trace_runs, warmup=1)
    n = len(shadow)
    sh = {"config": config_name(*key), "rays": n,
          "occluded_mrays_per_s": n / st["lantern:occluded"].median / 1e6,
          "closest_mrays_per_s": n / st["lantern:closest"].median / 1e6,
          "occluded_fraction": float(occ.out.mean()),
          "closest_hit_fraction": float((seg_closest.t >= 0).mean()),
          "closest_nodes_per_ray": float(seg_closest.stats[:, 0].mean()),
          "timing": {k: v.as_dict() for k, v in st.items()}}
    # a segment is occluded exactly when its closest hit lies inside it
    sh["consistent_with_closest"] = float((occ.out.astype(bool) == (seg_closest.t >= 0)).mean())
    if other_occ is not None:
        sh["other"] = {"config": config_name(*other[0]),
                       "occluded_mrays_per_s": n / st["lantern-other:occluded"].median / 1e6,
                       "agreement": float((other_occ.out == occ.out).mean())}
    if e_occ is not None:
        sh["embree_occluded_mrays_per_s"] = n / st["embree:occluded"].median / 1e6
        sh["embree_occluded_fraction"] = float(e_occ.out.mean())
        sh["agreement_with_embree"] = float((occ.out == e_occ.out).mean())
    return sh


def measure_mesh(name: str, tris: np.ndarray, config: BvhBenchConfig, embree=None, pool=None,
                 log=print) -> dict:
    """Build, trace and compare one mesh. `embree` is embree_side.load_embree()'s (module, class,
    version) or None; `pool` a thread pool for Embree's rays. Taichi must be initialised. Returns
    the mesh's part of the report (JSON-ready after common.write_json's conversion)."""
    n_tris = int(len(tris))
    large = n_tris >= SAH_BUILD_TARGET_MIN_TRIANGLES
    build_runs = config.build_runs_large if large else config.build_runs
    data = mesh_data(tris)
    t0 = time.perf_counter()
    lo, hi = data.bounds()
    bounds_s = time.perf_counter() - t0
    box_lo, box_hi = lo.min(axis=0), hi.max(axis=0)
    result = {"name": name, "triangles": n_tris, "bounds": [box_lo, box_hi], "bounds_s": bounds_s,
              "build_runs": build_runs, "configs": []}
    threads = int(ti.lang.impl.current_cfg().cpu_max_num_threads)

    # 1. builds, and a device copy of each tree for every traversal x triangle test
    result["builds"], geometries = _build_all(name, data, n_tris, config, build_runs, log)

    # 2. rays
    cw, chh = config.camera
    rays = {"coherent": camera_rays(box_lo, box_hi, cw, chh)}
    rays["incoherent"], shadow = random_rays(box_lo, box_hi, config.incoherent_rays, config.seed)
    result["rays"] = {"coherent": {"count": len(rays["coherent"]), "camera": [cw, chh]},
                      "incoherent": {"count": len(rays["incoherent"])}}
    emb, result["embree"] = _embree_mesh(name, tris, embree, threads, pool, rays["incoherent"].head(64), log)

    # compile every configuration on a handful of rays, then time all round-robin
    batches, calls, compile_s = {}, {}, {}
    for key, geometry in geometries.items():
        batches[key], compile_s[key] = _compiled_batch(geometry, rays["incoherent"])
        for kind, r in rays.items():
            calls[(key, kind)] = ClosestCall(batches[key], r)
    emb_calls = {kind: embree_side.EmbreeClosestCall(emb, r) for kind, r in rays.items()} if emb is not None else {}
    named = {f"{config_name(*key)}:{kind}": c for (key, kind), c in calls.items()}
    named.update({f"embree:{kind}": c for kind, c in emb_calls.items()})
    log(f"  {name}: timing {len(named)} ray calls x {config.trace_runs} runs ...")
    timings = time_interleaved(named, runs=config.trace_runs, warmup=1)

    for key in batches:
        entry = {"strategy": key[0], "traversal": key[1], "triangle_test": key[2], "compile_s": compile_s[key]}
        for kind in rays:
            c = calls[(key, kind)]
            s = c.summary(timings[f"{config_name(*key)}:{kind}"])
            if kind in emb_calls:
                e = emb_calls[kind]
                s["agreement"] = embree_side.agreement(c.t, e.t, e.hit)
            entry[kind] = s
        result["configs"].append(entry)
    for kind, e in emb_calls.items():
        result["embree"][kind] = e.summary(timings[f"embree:{kind}"])

    # the Renderer's configuration against Embree; the best configuration too
    default = next((c for c in result["configs"] if (c["strategy"], c["traversal"], c["triangle_test"]) == DEFAULT),
                   result["configs"][0])
    best = max(result["configs"], key=lambda c: c["incoherent"]["mrays_per_s"])
    default_key = (default["strategy"], default["traversal"], default["triangle_test"])
    result["default_config"] = config_name(*default_key)
    result["best_incoherent_config"] = config_name(best["strategy"], best["traversal"], best["triangle_test"])
    if emb is not None:
        result["ratio_to_embree"] = _embree_ratios(result, default, rays)
        result["embree_target_passed"] = result["ratio_to_embree"]["incoherent"]["default"] >= EMBREE_RATIO_TARGET
        per_kind = {}
        for kind, e in emb_calls.items():
            ok = np.ones(len(rays[kind]), bool)
            for key in batches:
                ok &= embree_side.compare(calls[(key, kind)].t, e.t, e.hit, embree_side.AGREEMENT_RTOL)[0]
            per_kind[kind] = float(ok.mean())
        result["agreement_all_configs"] = per_kind

    result["wide_vs_binary"] = wide_vs_binary(result["configs"])
    result["packets_vs_scalar"] = packets_vs_scalar(result["configs"])
    # any-hit (shadow) segments on the Renderer's configuration, and on the other tree (binary
    # "stack" against wide, or wide against a binary traversal), each with the default leaves
    if config.shadow_rays:
        base, leaves = traversal_and_leaves(default_key[1])
        other = ("stack" if base.startswith("wide") else WIDE) + (PACKETS if leaves == "packets" else "")
        other_key = (default_key[0], other, default_key[2])
        other = (other_key, batches[other_key]) if other_key in batches else None
        result["shadow"] = _shadow_rays(batches[default_key], default_key, shadow, emb, config, other)
    return result


def wide_vs_binary(configs: list) -> list:
    """Per strategy x triangle test x wide traversal (wide4, wide8; scalar leaves) measured with
    the binary "stack" traversal too: the wide traversal's rays/s over the binary one's (medians
    of the same interleaved runs), and their node visits."""
    by_key = {(c["strategy"], c["traversal"], c["triangle_test"]): c for c in configs}
    rows = []
    for (strategy, traversal, test), wide in by_key.items():
        binary = by_key.get((strategy, "stack", test))
        if not traversal.startswith("wide") or traversal.endswith(PACKETS) or binary is None:
            continue
        row = {"strategy": strategy, "triangle_test": test, "traversal": traversal}
        for kind in ("coherent", "incoherent"):
            row[kind] = {"speedup": wide[kind]["mrays_per_s"] / binary[kind]["mrays_per_s"],
                         "speedup_fastest_runs": wide[kind]["mrays_per_s_best"] / binary[kind]["mrays_per_s_best"],
                         "wide_nodes_per_ray": wide[kind]["nodes_per_ray"],
                         "binary_nodes_per_ray": binary[kind]["nodes_per_ray"]}
        rows.append(row)
    return rows


def packets_vs_scalar(configs: list) -> list:
    """Per strategy x traversal x triangle test measured with both leaf layouts: the packet
    leaves' rays/s over the scalar ones' (medians of the same interleaved runs)."""
    by_key = {(c["strategy"], c["traversal"], c["triangle_test"]): c for c in configs}
    rows = []
    for (strategy, traversal, test), packed in by_key.items():
        base, leaves = traversal_and_leaves(traversal)
        scalar = by_key.get((strategy, base, test))
        if leaves != "packets" or scalar is None:
            continue
        row = {"strategy": strategy, "traversal": base, "triangle_test": test}
        for kind in ("coherent", "incoherent"):
            row[kind] = {"speedup": packed[kind]["mrays_per_s"] / scalar[kind]["mrays_per_s"],
                         "speedup_fastest_runs": packed[kind]["mrays_per_s_best"] / scalar[kind]["mrays_per_s_best"],
                         "tests_per_ray": packed[kind]["tests_per_ray"]}
        rows.append(row)
    return rows


def leaf_size_sweep(name: str, tris: np.ndarray, config: BvhBenchConfig, log=print) -> dict:
    """SAH builds with each max_leaf_size: build time, bytes/triangle, incoherent Mrays/s."""
    n_tris = int(len(tris))
    data = mesh_data(tris)
    lo, hi = data.bounds()
    centroids = 0.5 * (lo + hi)
    rays, _ = random_rays(lo.min(axis=0), hi.max(axis=0), config.incoherent_rays, config.seed)
    runs = config.build_runs_large if n_tris >= SAH_BUILD_TARGET_MIN_TRIANGLES else config.build_runs
    rows, calls = [], {}
    for leaf in config.leaf_sizes:
        bvh, timing = timed_builds(lo, hi, centroids, "sah", leaf, runs)
        geometry = make_geometry(data, bvh, DEFAULT[1], DEFAULT[2])
        batch, compile_s = _compiled_batch(geometry, rays)
        calls[leaf] = ClosestCall(batch, rays)
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
    return {"mesh": name, "triangles": n_tris, "config": config_name("sah", *DEFAULT[1:]), "rays": len(rays),
            "rows": rows, "best_max_leaf_size": best["max_leaf_size"], "within_tie_of_best": near,
            "tie_fraction": LEAF_TIE, "renderer_default": PACKET_LEAF if DEFAULT[1].endswith(PACKETS) else DEFAULT_LEAF}

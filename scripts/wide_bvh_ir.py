"""What LLVM makes of the wide BVH's node test and the packet leaves' triangle test: compiles them
(and the whole closest-hit traversal) with Taichi's optimised LLVM IR and assembly written out,
and counts the 4-lane instructions.

    python scripts/wide_bvh_ir.py [--keep DIR] [--optimize compile|run] [--only node,node8,leaf,traversal]

Kernels, each on Taichi's CPU back-end with the offline cache off (so the files are written):
  node:      a stand-alone loop over rays that visits one wide node each (WideNodes.visit)
  node8:     the same with 8-wide nodes (`<8 x float>` counts)
  leaf:      a stand-alone loop over rays that tests one packet of four triangles each
             (TrianglePackets.watertight and nearest_lane, as the packet leaves call them)
  traversal: renderer.bench.ray_batch's closest-hit kernel over a small mesh with the Renderer's
             traversal (MeshOptions: 8-wide) and packet leaves
For each: `<4 x float>` values in the optimised IR (loads, fsub/fmul, minnum/maxnum, fcmp) and
packed (`ps`) against scalar (`ss`) subtract/multiply/min/max instructions in the assembly. The
node test has vectorised when its subtractions, multiplications, minima and maxima are packed.
"""
import argparse
import os
import re
import sys
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

IR_PATTERNS = {
    "load <4 x float>": r"= load <4 x float>",
    "fsub/fmul <4 x float>": r"= f(?:sub|mul) [a-z ]*<4 x float>",
    "minnum/maxnum <4 x float>": r"= call [a-z ]*<4 x float> @llvm\.(?:min|max)num\.v4f32\(",
    "fcmp <4 x float>": r"= fcmp [a-z ]*<4 x float>",
    "fsub/fmul <2 x float>": r"= f(?:sub|mul) [a-z ]*<2 x float>",
    "load <8 x float>": r"= load <8 x float>",
    "fsub/fmul <8 x float>": r"= f(?:sub|mul) [a-z ]*<8 x float>",
    "fcmp <8 x float>": r"= fcmp [a-z ]*<8 x float>",
    "minnum/maxnum <2 x float>": r"= call [a-z ]*<2 x float> @llvm\.(?:min|max)num\.v2f32\(",
}
ASM_OPS = ("vsub", "vmul", "vmin", "vmax", "vcmp")


def count_files(directory: Path) -> dict:
    """Counts over every .ll and .s file Taichi wrote into `directory`."""
    ir = "\n".join(p.read_text() for p in sorted(directory.glob("*.ll")))
    asm = "\n".join(p.read_text() for p in sorted(directory.glob("*.s")))
    out = {name: len(re.findall(pattern, ir)) for name, pattern in IR_PATTERNS.items()}
    ops = Counter(re.findall(r"\b(v(?:sub|mul|min|max|cmp)[a-z]*(?:ps|ss))\b", asm))
    for op in ASM_OPS:
        out[f"{op}*ps (packed)"] = sum(n for name, n in ops.items() if name.startswith(op) and name.endswith("ps"))
        out[f"{op}*ss (scalar)"] = sum(n for name, n in ops.items() if name.startswith(op) and name.endswith("ss"))
    return out


def compile_node_kernel(width: int = 4):
    import taichi as ti

    from renderer.geometry.wide_bvh import collapse
    from renderer.geometry.bvh_build import build_bvh
    from renderer.geometry.wide_traversal import WideNodes, plane_rows
    from renderer.runtime.upload import upload_fields

    rng = np.random.default_rng(0)
    lo = rng.uniform(-1, 1, (64, 3))
    wide = collapse(build_bvh(lo, lo + 0.1, lo + 0.05), width=width)
    uploads = []
    nodes = WideNodes(wide, uploads)
    upload_fields(uploads)

    @ti.kernel
    def node_test(o: ti.types.ndarray(), d: ti.types.ndarray(), out: ti.types.ndarray(), refs: ti.types.ndarray()):
        for i in range(o.shape[0]):
            origin = ti.math.vec3(o[i, 0], o[i, 1], o[i, 2])
            direction = ti.math.vec3(d[i, 0], d[i, 1], d[i, 2])
            inv_d = 1.0 / ti.select(ti.abs(direction) > 1e-30, direction, 1e-30)
            near, far = plane_rows(direction)
            stack_ref = ti.Vector([0] * (2 * width), dt=ti.i32)
            stack_t = ti.Vector([0.0] * (2 * width), dt=ti.f32)
            ref, found, sp = nodes.visit(i % nodes.count, origin, inv_d, near, far, 1e30, stack_ref, stack_t, 0)
            refs[i, 0] = ref if found else -1
            for c in ti.static(range(width - 1)):
                out[i, c] = stack_t[c] if c < sp else -1.0
                refs[i, c + 1] = stack_ref[c] if c < sp else -1

    n = 16
    node_test(rng.normal(size=(n, 3)).astype(np.float32), rng.normal(size=(n, 3)).astype(np.float32),
              np.zeros((n, width - 1), np.float32), np.zeros((n, width), np.int32))


def compile_leaf_kernel():
    import taichi as ti

    from renderer.geometry.intersect import watertight_setup
    from renderer.geometry.triangle_packets import TrianglePackets, build_packets, nearest_lane, permuted_origin
    from renderer.runtime.upload import upload_fields

    rng = np.random.default_rng(0)
    tris = rng.normal(size=(64, 3, 3)).astype(np.float32)
    uploads = []
    packets = TrianglePackets(build_packets(np.arange(64), tris), uploads)
    upload_fields(uploads)

    @ti.kernel
    def leaf_test(o: ti.types.ndarray(), d: ti.types.ndarray(), t_max: ti.types.ndarray(), out: ti.types.ndarray()):
        for i in range(o.shape[0]):
            origin = ti.math.vec3(o[i, 0], o[i, 1], o[i, 2])
            direction = ti.math.vec3(d[i, 0], d[i, 1], d[i, 2])
            k, s = watertight_setup(direction)
            # t_max read at run time, as the traversal's closest hit so far is (a constant would
            # let the compiler fold what the test keeps opaque)
            found, t, b1, b2 = packets.watertight(i % packets.count, permuted_origin(origin, k), k, s, t_max[i])
            t_near, lane, u, v = nearest_lane(found & packets.lane_mask(i % packets.count, 1, 4 * packets.count), t,
                                              b1, b2)
            out[i, 0] = t_near
            out[i, 1] = lane
            out[i, 2] = u
            out[i, 3] = v

    n = 16
    leaf_test(rng.normal(size=(n, 3)).astype(np.float32), rng.normal(size=(n, 3)).astype(np.float32),
              np.full(n, 1e30, np.float32), np.zeros((n, 4), np.float32))


def compile_traversal_kernel():
    from renderer.bench.ray_batch import RayBatch
    from renderer.geometry.mesh_data import MeshData
    from renderer.geometry.mesh_geometry import MeshGeometry
    from renderer.geometry.bvh_build import build_bvh
    from renderer.renderer import MeshOptions

    rng = np.random.default_rng(0)
    tris = (rng.uniform(-1, 1, (200, 1, 3)) + rng.normal(0, 0.1, (200, 3, 3))).astype(np.float32)
    data = MeshData(tri_vertices=tris, tri_material=np.zeros(200, np.int32))
    lo, hi = data.bounds()
    geometry = MeshGeometry(data, build_bvh(lo, hi, 0.5 * (lo + hi)), MeshOptions().traversal,
                            leaves="packets")
    n = 16
    RayBatch(geometry).closest(rng.normal(size=(n, 3)).astype(np.float32) * 3,
                               rng.normal(size=(n, 3)).astype(np.float32), np.full(n, 1e30, np.float32),
                               np.zeros(n, np.float32), np.zeros(n, np.int32), np.zeros((n, 2), np.int32))


def run_in(directory: Path, which: str, optimize: str = "run") -> dict:
    """Compile one kernel set in a fresh Taichi runtime with `directory` as the working directory
    (where Taichi writes its .ll and .s files), and count."""
    import taichi as ti

    directory.mkdir(parents=True, exist_ok=True)
    cwd = os.getcwd()
    os.chdir(directory)
    try:
        from renderer.runtime.arch import cpu_scheduling_options, taichi_options

        ti.init(arch=ti.cpu, offline_cache=False, print_kernel_llvm_ir_optimized=True, print_kernel_asm=True,
                log_level=ti.WARN, **taichi_options(optimize), **cpu_scheduling_options())
        {"node": compile_node_kernel, "node8": lambda: compile_node_kernel(8), "leaf": compile_leaf_kernel,
         "traversal": compile_traversal_kernel}[which]()
        ti.reset()
    finally:
        os.chdir(cwd)
    return count_files(directory)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--keep", type=Path, help="write the .ll and .s files here (default: a temporary folder)")
    parser.add_argument("--optimize", choices=("compile", "run"), default="run",
                        help="Taichi's optimisation level (renderer/runtime/arch.py): run (benchmarks, long renders) or "
                             "compile (the viewer's and the tests'); LLVM optimises both")
    parser.add_argument("--only", default="node,node8,leaf,traversal", help="which kernels (comma-separated)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        root = args.keep or Path(tmp)
        for which in args.only.split(","):
            counts = run_in(root / which, which, args.optimize)
            print(f"{which}: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
        if args.keep:
            print(f"files in {args.keep}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

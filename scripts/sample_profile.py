"""Where the time of a sample goes, by ablation: Taichi's JIT code has no symbols a sampling
profiler could name, so the costs are measured by running less of the work.

    .venv/bin/python scripts/sample_profile.py [scene ...] [--size 256] [--spp 8] [--runs 5]
                                               [--optimize run|compile] [--nodes-only]
                                               [--texture-filter anisotropic|trilinear|none]
                                               [--packets 4|8|16]

Two tables per scene (milliseconds per sample per pixel at --size x --size, median of --runs
launches of --spp samples each, after a launch that compiles):

1. Integrators: `normals` (one camera ray and its hit), `path` at max depth 1, 2, 4 and 8, `nee`
   and `mis` at depth 8, and `mis` with the Sobol sampler; with the rays each traces per sample
   (the film's work counters), so ms per ray follows.
2. Stages of one bounce, each kernel doing one step more than the one before: generate the
   camera ray; + trace it (closest hit); + the surface record; + shading (material lookup, shading
   frame); + sampling the BSDF; + tracing the bounce ray. Beside them, from the BSDF sample on: a
   light sample (`sample_direct`, with the BSDF's value and MIS weight), and + its shadow ray
   (any hit). The increments are the stages' costs.

With --packets N, the integrators table renders with packets of N rays where the scene takes them
(renderer/packets/), and table 2 is measured again for the packet path, with the same rows made of
its lane-by-lane pieces: N neighbouring pixels of a row a packet, shading as the packet path's
Lambert lobe.

With --nodes-only, table 2 is measured again with the leaf tests replaced by a stub that only
counts (traversal of the nodes alone; rays then miss, so only the first two rows mean anything).
"""

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

INTEGRATOR_ROWS = (("normals", 1, "independent"), ("path", 1, "independent"), ("path", 2, "independent"),
                   ("path", 4, "independent"), ("path", 8, "independent"), ("nee", 8, "independent"),
                   ("mis", 8, "independent"), ("mis", 8, "sobol"))
STAGES = ("camera ray", "+ trace (closest hit)", "+ surface record", "+ shading", "+ BSDF sample",
          "+ trace the bounce ray")
LIGHT_STAGES = ("BSDF sample + light sample", "+ shadow ray (any hit)")


def median_ms_per_spp(launch, spp: int, runs: int) -> float:
    import taichi as ti

    launch(1, 0)
    ti.sync()
    times = []
    for k in range(runs):
        start = time.perf_counter()
        launch(spp, k + 1)
        ti.sync()
        times.append(time.perf_counter() - start)
    return statistics.median(times) / spp * 1e3


def stage_kernels(program, width: int, height: int):
    """A data-oriented object whose kernel `run(stage, ...)` does stages 0..stage of one bounce
    (stage 6: the light sample after stage 4, stage 7: with its shadow ray)."""
    import taichi as ti

    from renderer.camera import generate_ray
    from renderer.geometry.interface import INF
    from renderer.integrators.light_sampling import sample_direct
    from renderer.sampling import dims

    out = ti.Vector.field(3, ti.f32, shape=(width, height))

    @ti.data_oriented
    class Stages:
        def __init__(self, ctx):
            self.ctx = ctx

        @ti.kernel
        def run(self, stage: ti.template(), spp: ti.i32, seed: ti.u32, origin: ti.math.vec3,
                forward: ti.math.vec3, right: ti.math.vec3, up: ti.math.vec3, half_height: ti.f32,
                aperture: ti.f32, focus: ti.f32):
            ctx = self.ctx
            for x, y in ti.ndrange(width, height):
                acc = ti.math.vec3(0.0)
                for s in range(spp):
                    state = ctx.sampler.start(y * width + x, s, seed)
                    ray = generate_ray(x, y, width, height, ctx.sampler.get2d(state, dims.PIXEL), ctx.sampler, state,
                                       origin, forward, right, up, half_height, aperture, focus, False,
                                       False)
                    v = ray.d  # every stage adds to it, so that none is dead code
                    if ti.static(stage >= 1):
                        hit = ctx.geometry.trace(ray, INF, False)
                        v.x += hit.t
                        if ti.static(stage >= 2):
                            if hit.hit == 1:
                                srf = ctx.geometry.surface(ray, hit)
                                v += srf.n_shading
                                if ti.static(stage >= 3):
                                    mat, n = ctx.bsdf.shade(srf, -ray.d)
                                    v += n
                                    if ti.static(stage >= 4):
                                        bs = ctx.bsdf.sample_at(mat, n, srf.n_geo, -ray.d,
                                                                ctx.sampler.get1d(state, dims.BOUNCE_BASE),
                                                                ctx.sampler.get2d(state, dims.BOUNCE_BASE + 1))
                                        v += bs.weight * bs.wi
                                        if ti.static(stage == 5):
                                            ray2, t2 = ctx.geometry.next_segment(srf, bs.wi, ti.math.vec3(0.0),
                                                                                 ti.math.vec3(0.0), False)
                                            v.y += ctx.geometry.trace(ray2, t2, False).t
                                        if ti.static(stage >= 6):
                                            found, ls, f, scale = sample_direct(
                                                ctx, True, mat, n, srf, -ray.d,
                                                ctx.sampler.get1d(state, dims.BOUNCE_BASE + dims.LIGHT_SELECT),
                                                ctx.sampler.get2d(state, dims.BOUNCE_BASE + dims.LIGHT_POINT))
                                            v += f * ls.radiance * scale
                                            if ti.static(stage == 7):
                                                if found:
                                                    ray3, t3 = ctx.geometry.next_segment(srf, ls.wi, ls.p, ls.n, True)
                                                    v.z += ctx.geometry.trace(ray3, t3, True).hit
                    acc += v
                out[x, y] = acc

    return Stages(program)


def packet_stage_kernels(program, width: int, height: int):
    """stage_kernels' rows for a PacketProgram: `run(stage, ...)` does stages 0..stage of one
    bounce for packets of program.width neighbouring pixels (width a multiple of it)."""
    import taichi as ti

    from renderer.camera import pinhole_ray
    from renderer.geometry.interface import INF
    from renderer.packets import traversal
    from renderer.packets.lanes import cosine_hemisphere
    from renderer.packets.path import leave, uniform2
    from renderer.packets.surfaces import hit_surface
    from renderer.sampling import dims
    from renderer.sampling.rng import sample_key, uniform

    lanes = program.width
    if program.has_general or program.shading_normals:
        raise SystemExit("the packet stage table shades Lambert lanes about the geometric normal only: this "
                         "scene's lanes take the scalar BSDF (materials other than Lambert's, textures or maps) "
                         "or vertex normals")
    if width % lanes:
        raise SystemExit(f"--size must be a multiple of the packet width {lanes}")
    out = ti.field(ti.f32, shape=(width // lanes, height))

    @ti.data_oriented
    class PacketStages:
        def __init__(self, ctx):
            self.ctx = ctx

        @ti.kernel
        def run(self, stage: ti.template(), spp: ti.i32, seed: ti.u32, origin: ti.math.vec3,
                forward: ti.math.vec3, right: ti.math.vec3, up: ti.math.vec3, half_height: ti.f32,
                aperture: ti.f32, focus: ti.f32):
            ctx = self.ctx
            n = ti.static(lanes)
            for p, y in ti.ndrange(width // n, height):
                acc = 0.0
                for s in range(spp):
                    key = ti.Vector([0] * n, dt=ti.u32)
                    xs = ti.Vector([0.0] * n, dt=ti.f32)
                    for k in range(n):
                        key[k] = sample_key(ti.cast(y * width + p * n + k, ti.u32), s, seed)
                        xs[k] = p * n + k
                    jx, jy = uniform2(key, dims.PIXEL)
                    u = 2.0 * (xs + jx) / width - 1.0
                    v = 2.0 * (y + jy) / height - 1.0
                    ox, oy, oz = jx * 0.0, jx * 0.0, jx * 0.0
                    dx, dy, dz = jx * 0.0, jx * 0.0, jx * 0.0
                    for k in range(n):
                        o, d = pinhole_ray(u[k], v[k], width / height, origin, forward, right, up, half_height,
                                           False)
                        ox[k], oy[k], oz[k] = o.x, o.y, o.z
                        dx[k], dy[k], dz[k] = d.x, d.y, d.z
                    val = dx + dy + dz  # every stage adds to it, so that none is dead code
                    if ti.static(stage >= 1):
                        prim, t, b1, b2, visits, tests = traversal.trace(ctx.geometry, ox, oy, oz, dx, dy, dz,
                                                                         val * 0.0 + INF, False)
                        val += t
                        if ti.static(stage >= 2):
                            live = prim >= 0
                            px, py, pz, nx, ny, nz, eps, material = hit_surface(
                                ctx.records, ti.static("sphere" in ctx.geometry.kinds), prim, t, b1, b2,
                                ox, oy, oz, dx, dy, dz)
                            val += nx + ny + nz
                            if ti.static(stage >= 3):
                                ar, ag, ab = val * 0.0, val * 0.0, val * 0.0
                                for k in ti.static(range(n)):
                                    row = ctx.materials.table[material[k]]
                                    ar[k], ag[k], ab[k] = row.base_color.x, row.base_color.y, row.base_color.z
                                cos_o = -(dx * nx + dy * ny + dz * nz)
                                side = ti.select(cos_o >= 0.0, 1.0, -1.0)
                                fx, fy, fz = side * nx, side * ny, side * nz
                                val += ar + ag + ab
                                if ti.static(stage >= 4):
                                    v1, v2 = uniform2(key, dims.BOUNCE_BASE + dims.BSDF_DIRECTION)
                                    wx, wy, wz, cos_t = cosine_hemisphere(v1, v2, fx, fy, fz)
                                    val += wx * ar + wy * ag + wz * ab
                                    if ti.static(stage == 5):
                                        sx, sy, sz = leave(px, py, pz, nx, ny, nz, eps, wx * nx + wy * ny + wz * nz)
                                        prim2, t2, c1, c2, v2_, n2_ = traversal.trace(
                                            ctx.geometry, sx, sy, sz, wx, wy, wz, ti.select(live, INF, -1.0), False)
                                        val += t2
                                    if ti.static(stage >= 6):
                                        l1, l2 = uniform2(key, dims.BOUNCE_BASE + dims.LIGHT_POINT)
                                        qwx, qwy, qwz, dist, pdf, qx, qy, qz, qnx, qny, qnz, rr, rg, rb, light = \
                                            ctx.lights.sample(px, py, pz,
                                                              uniform(key, dims.BOUNCE_BASE + dims.LIGHT_SELECT),
                                                              l1, l2)
                                        val += (qwx * fx + qwy * fy + qwz * fz) * (rr + rg + rb) / ti.max(pdf, 1e-30)
                                        if ti.static(stage == 7):
                                            sx, sy, sz = leave(px, py, pz, nx, ny, nz, eps,
                                                               qwx * nx + qwy * ny + qwz * nz)
                                            gx, gy, gz = qx - sx, qy - sy, qz - sz
                                            length = ti.sqrt(gx * gx + gy * gy + gz * gz)
                                            inv_len = 1.0 / ti.max(length, 1e-30)
                                            t_max = ti.select(live & (pdf > 0.0), length * (1.0 - 1e-4), -1.0)
                                            blocker, tb, c1, c2, v3_, n3_ = traversal.trace(
                                                ctx.geometry, sx, sy, sz, gx * inv_len, gy * inv_len, gz * inv_len,
                                                t_max, True)
                                            val += ti.cast(blocker, ti.f32)
                    acc += val.sum()
                out[p, y] = acc

    return PacketStages(program)


def stub_leaf_tests() -> None:
    """Replace the mesh leaf test by a counter (before any kernel compiles)."""
    import taichi as ti

    from renderer.geometry import mesh_geometry

    @ti.func
    def count_only(self, first, count, o, d, k, s, hit: ti.template(), any_hit, ray, instance):
        hit.tests += count

    mesh_geometry.MeshGeometry.test_leaf = count_only


def profile(scene_name: str, args) -> None:
    from renderer.camera import CameraFrame
    from renderer.renderer import MeshOptions, Renderer
    from renderer.scene.catalog import load_any, resolve_scene

    scene = load_any(resolve_scene(scene_name))
    if args.texture_filter is not None:
        from dataclasses import replace

        scene = replace(scene, render=replace(scene.render, texture_filter=args.texture_filter))
    size = args.size
    renderer = Renderer(scene, (size, size), MeshOptions(packets=args.packets))
    camera = CameraFrame.from_spec(scene.camera)
    title = f"{scene.name} {size}x{size}, ms per spp (median of {args.runs} launches of {args.spp} spp)"
    if args.texture_filter is not None:
        title += f", texture filter {args.texture_filter}"
    if args.packets:
        reason = renderer.packet_reason("mis", renderer.features(camera), "independent")
        taken = "taken" if reason is None else f"not taken, {reason}"
        title += f", packets of {args.packets} rays: {taken}"
    if not args.nodes_only:
        print(f"\n{title}: integrators")
        print(f"{'integrator':10s} {'depth':>5s} {'sampler':12s} {'ms/spp':>8s} {'rays/sample':>11s} {'ms/spp/ray':>10s}")
        for integrator, depth, sampler in INTEGRATOR_ROWS:
            def launch(spp, seed, integrator=integrator, depth=depth, sampler=sampler):
                renderer.reset()
                renderer.render(camera, spp, integrator, max_depth=depth, sampler=sampler, seed=seed)

            ms = median_ms_per_spp(launch, args.spp, args.runs)
            rays = float(renderer.work_stats()["rays_per_sample"])
            print(f"{integrator:10s} {depth:5d} {sampler:12s} {ms:8.2f} {rays:11.2f} {ms / rays:10.2f}", flush=True)
    program = renderer.program("mis", renderer.features(camera), "independent")
    packed = hasattr(program, "occupancy")
    kernels = packet_stage_kernels(program, size, size) if packed else stage_kernels(program, size, size)
    args_k = camera.kernel_args()
    print(f"\n{title}: stages of one bounce" + (" (leaf tests stubbed)" if args.nodes_only else "")
          + (f", the packet path's pieces" if packed else ""))
    measured = {}
    for stage, name in enumerate(STAGES):
        measured[stage] = median_ms_per_spp(lambda spp, seed, stage=stage: kernels.run(stage, spp, seed, *args_k),
                                            args.spp, args.runs)
        print(f"{name:28s} {measured[stage]:8.2f}  (+{measured[stage] - measured.get(stage - 1, 0.0):6.2f})",
              flush=True)
    previous = measured[4]
    for stage, name in zip((6, 7), LIGHT_STAGES):
        ms = median_ms_per_spp(lambda spp, seed, stage=stage: kernels.run(stage, spp, seed, *args_k), args.spp,
                               args.runs)
        print(f"{name:28s} {ms:8.2f}  (+{ms - previous:6.2f})", flush=True)
        previous = ms


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenes", nargs="*", default=["cornell_box"])
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--spp", type=int, default=8)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--optimize", choices=("run", "compile"), default="run")
    parser.add_argument("--nodes-only", action="store_true", help="stub the leaf tests (nodes alone)")
    parser.add_argument("--texture-filter", choices=("anisotropic", "trilinear", "none"),
                        help="the scenes' render.texture_filter (default: each scene's own)")
    parser.add_argument("--packets", type=int, choices=(0, 4, 8, 16), default=0,
                        help="render with packets of this many rays where the scene takes them")
    args = parser.parse_args(argv)
    if args.packets and args.nodes_only:
        parser.error("--nodes-only stubs the scalar leaf tests; it does not apply to --packets")

    from renderer.runtime.arch import init_taichi

    init_taichi("cpu", optimize=args.optimize)
    if args.nodes_only:
        stub_leaf_tests()
    for name in args.scenes:
        profile(name, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Where the time of a sample goes, by ablation: Taichi's JIT code has no symbols a sampling
profiler could name, so the costs are measured by running less of the work.

    .venv/bin/python scripts/sample_profile.py [scene ...] [--size 256] [--spp 8] [--runs 5]
                                               [--optimize run|compile] [--nodes-only]
                                               [--texture-filter anisotropic|trilinear|none]

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
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any, resolve_scene

    scene = load_any(resolve_scene(scene_name))
    if args.texture_filter is not None:
        from dataclasses import replace

        scene = replace(scene, render=replace(scene.render, texture_filter=args.texture_filter))
    size = args.size
    renderer = Renderer(scene, (size, size))
    camera = CameraFrame.from_spec(scene.camera)
    title = f"{scene.name} {size}x{size}, ms per spp (median of {args.runs} launches of {args.spp} spp)"
    if args.texture_filter is not None:
        title += f", texture filter {args.texture_filter}"
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
    kernels = stage_kernels(program, size, size)
    args_k = camera.kernel_args()
    print(f"\n{title}: stages of one bounce" + (" (leaf tests stubbed)" if args.nodes_only else ""))
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
    args = parser.parse_args(argv)

    from renderer.runtime.arch import init_taichi

    init_taichi("cpu", optimize=args.optimize)
    if args.nodes_only:
        stub_leaf_tests()
    for name in args.scenes:
        profile(name, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())

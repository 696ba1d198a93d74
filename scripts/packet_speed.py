"""Packets against one ray at a time, measured in one process and interleaved: closest hits plus
shadow flags of the same rays (camera rays through a grid, and random rays in the scene's box),
and whole renders (samples per second), for each packet width. Prints medians and writes JSON.

    python scripts/packet_speed.py [--scenes cornell_box] [--size 256] [--spp 64] [--rounds 5]
        [--widths 8,16] [--optimize compile|run] [--out reports/packet_speed.json]

Samples per second compare estimators only where they are the same: the packet path selects
lights by power where the scalar path may use its light tree. So each width also gets an
equal-error speed: (v t) of one ray at a time over (v t) of the width, with t the median render
time and v the median over pixels of the variance of the pixel's mean (medians: caustic
fireflies make the mean variance of a few renders meaningless).

The first render of each width compiles its kernel: its time is reported apart (cold where
Taichi's offline cache has not seen the kernel yet).
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


def camera_rays(scene, size):
    from renderer.camera import CameraFrame

    cam = CameraFrame.from_spec(scene.camera)
    xs, ys = np.meshgrid(np.arange(size), np.arange(size))
    u = (2 * (xs.ravel() + 0.5) / size - 1) * cam.half_height
    v = (2 * (ys.ravel() + 0.5) / size - 1) * cam.half_height
    d = np.asarray(cam.forward) + u[:, None] * np.asarray(cam.right) + v[:, None] * np.asarray(cam.up)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.tile(np.asarray(cam.position, np.float32), (len(d), 1)), d.astype(np.float32)


def box_rays(data, n, seed=1):
    lo, hi = (np.asarray(a) for a in data.scene_bounds())
    rng = np.random.default_rng(seed)
    o = lo + (hi - lo) * rng.random((n, 3))
    d = rng.normal(size=(n, 3))
    return o.astype(np.float32), (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)


def timed(fn, rounds):
    fn()
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return times


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="cornell_box")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--widths", default="8,16")
    parser.add_argument("--optimize", choices=("compile", "run"), default="compile",
                        help="kernel optimisation level (render's own for mesh scenes: compile; run compiles a "
                             "scene of many material kinds for many minutes)")
    parser.add_argument("--out", type=Path, default=Path("reports/packet_speed.json"))
    args = parser.parse_args(argv)
    import taichi as ti

    from renderer.runtime.arch import cpu_scheduling_options, taichi_options

    ti.init(arch=ti.cpu, log_level=ti.WARN, **taichi_options(args.optimize), **cpu_scheduling_options())
    from renderer.bench.packet_rays import PacketShooter
    from renderer.bench.ray_batch import RayBatch
    from renderer.camera import CameraFrame
    from renderer.geometry.interface import INF
    from renderer.renderer import MeshOptions, Renderer
    from renderer.scene.catalog import load_any

    widths = [int(w) for w in args.widths.split(",")]
    report = {"size": args.size, "spp": args.spp, "rounds": args.rounds, "scenes": {}}
    for name in args.scenes.split(","):
        scene = load_any(name if name.endswith((".toml", ".xml", ".pbrt")) else f"assets/scenes/{name}.toml")
        camera = CameraFrame.from_spec(scene.camera)
        renderers, first = {}, {}
        for w in [0] + widths:
            start = time.perf_counter()
            r = Renderer(scene, (args.size, args.size), MeshOptions(packets=w))
            r.render(camera, 1)
            ti.sync()
            renderers[w], first[w] = r, time.perf_counter() - start
        entry = {"first_render_s": first, "reason": renderers[widths[0]].packet_reason(
            scene.render.integrator, renderers[0].features(camera), scene.render.sampler)}
        # rays: closest hit and shadow flag of each ray, one kernel call each
        geometry = renderers[0].geometry
        rays = {"camera": camera_rays(scene, args.size), "random": box_rays(geometry.data, args.size * args.size)}
        shooters = {0: RayBatch(geometry)} | {w: PacketShooter(geometry, w) for w in widths}
        ray_rates = {}
        for kind, (o, d) in rays.items():
            n = len(o)
            t_max = np.full(n, INF, np.float32)

            def scalar_rays():
                shooters[0].closest(o, d, t_max, np.zeros(n, np.float32), np.zeros(n, np.int32),
                                    np.zeros((n, 2), np.int32))
                shooters[0].occluded(o, d, t_max, np.zeros(n, np.int32))
                ti.sync()

            times = {w: [] for w in [0] + widths}
            for _ in range(args.rounds):  # interleaved
                times[0] += timed(scalar_rays, 1)
                for w in widths:
                    times[w] += timed(lambda: (shooters[w].closest(o, d), shooters[w].occluded(o, d)), 1)
            ray_rates[kind] = {w: 2 * n / float(np.median(ts)) / 1e6 for w, ts in times.items()}
        entry["mrays_per_s"] = ray_rates
        times = {w: [] for w in renderers}
        variances = {w: [] for w in renderers}
        for k in range(args.rounds):
            for w, r in renderers.items():
                r.reset()
                start = time.perf_counter()
                r.render(camera, args.spp, seed=k)
                ti.sync()
                times[w].append(time.perf_counter() - start)
                variances[w].append(float(np.median(r.film.variance_of_mean_image().sum(axis=-1))))
        samples = args.size * args.size * args.spp
        entry["msamples_per_s"] = {w: samples / float(np.median(ts)) / 1e6 for w, ts in times.items()}
        cost = {w: float(np.median(times[w])) * float(np.median(variances[w])) for w in renderers}
        entry["median_pixel_variance"] = {w: float(np.median(v)) for w, v in variances.items()}
        entry["equal_error_speed"] = {w: cost[0] / cost[w] if cost[w] > 0 else None for w in renderers}
        entry["image_mean"] = {w: r.image().reshape(-1, 3).mean(axis=0).tolist() for w, r in renderers.items()}
        entry["occupancy"] = {}
        for w in widths:
            program = renderers[w].program(scene.render.integrator, renderers[w].features(camera),
                                           scene.render.sampler)
            if hasattr(program, "occupancy"):
                entry["occupancy"][w] = program.occupancy()
        report["scenes"][name] = entry
        print(f"{name}: packets {entry['reason'] or 'taken'}")
        for w in renderers:
            speed = entry["equal_error_speed"][w]
            line = (f"  width {w or 1:2d}: render {entry['msamples_per_s'][w]:.2f} M samples/s "
                    f"({entry['msamples_per_s'][w] / entry['msamples_per_s'][0]:.2f}x; at equal error "
                    f"{speed if speed is None else round(speed, 2)}x), first render "
                    f"{first[w]:.1f} s; closest + shadow rays: camera {ray_rates['camera'][w]:.2f}, random "
                    f"{ray_rates['random'][w]:.2f} M rays/s")
            occupancy = entry["occupancy"].get(w)
            if occupancy:
                line += (f"; lanes live: closest {occupancy['closest']:.0%}, shadow "
                         f"{occupancy['shadow']:.0%}" if occupancy["shadow"] is not None else "")
            print(line)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1, default=str))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

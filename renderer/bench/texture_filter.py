"""`python app.py bench texture-filter`: what texture filtering (RenderSettings.texture_filter:
none, trilinear, anisotropic) costs in time and buys in error.

1. Error against time on the checker horizon (renderer/bench/checker_horizon.py), `path`: for each
   filter, renders of 1, 4, 16 and 64 spp (each from an empty film, on seeds of its own), their
   RMSE against an unfiltered render of `reference_spp`, and their render seconds. At low sample
   counts the error there is all aliasing; filtering trades it for a blur that fades as a pixel's
   cone narrows with its samples (renderer/geometry/texture_footprint.py).
2. Speed: samples per second of `mis` on the textured scene (glTF base colour, metallic-roughness
   and normal map textures) at `size` for each filter, and on the Cornell box (no textures: every
   filter compiles the same kernel), in interleaved rounds, medians.
3. The denoising target on textured at `size` (the issue's 320x180): relMSE of the 8-spp render
   denoised (AOVs prefiltered, as `render --denoise`; and the noisy AOVs passed straight in, the
   viewer's first denoise) and of the raw 128-spp render, each less the reference's own noise,
   against one reference of `reference_s` seconds (unfiltered: filtered renders converge to it).
   Render seconds exclude the denoiser.

Writes <out_dir>/bench_texture_filter.json and bench_texture_filter.png (error against seconds).
"""
from __future__ import annotations

import statistics
import time
import warnings
from dataclasses import asdict, dataclass, replace
from pathlib import Path


from renderer.bench.common import (describe_error, load_average, load_named_scene, log, print_table, pyplot, rel_mse,
                                   report_header, rmse, save_figure, speed_runtime, write_json)
from renderer.bench.convergence import sync
from renderer.scene.textures import TEXTURE_FILTERS


@dataclass(frozen=True)
class TextureFilterBenchConfig:
    horizon_size: tuple[int, int] = (160, 80)
    horizon_spp: tuple[int, ...] = (1, 4, 16, 64)
    reference_spp: int = 4096
    size: tuple[int, int] = (320, 180)
    speed_spp: int = 32
    rounds: int = 5
    reference_s: float = 120.0
    target_spp: tuple[int, int] = (8, 128)  # denoised at the first below raw at the second
    seed: int = 1
    reference_seed: int = 7919


FULL = TextureFilterBenchConfig()
QUICK = TextureFilterBenchConfig(horizon_size=(64, 32), horizon_spp=(1, 4, 16), reference_spp=512, size=(96, 54),
                                 speed_spp=8, rounds=2, reference_s=8.0, target_spp=(8, 32))


def timed(renderer, camera, spp: int, integrator: str, seed: int) -> float:
    t0 = time.perf_counter()
    renderer.render(camera, spp, integrator, seed=seed)
    sync()
    return time.perf_counter() - t0


def horizon_curves(config: TextureFilterBenchConfig) -> dict:
    """{filter: [{"spp", "seconds", "rmse"}]} on the checker horizon, and the reference's spp."""
    from renderer.bench.checker_horizon import checker_horizon
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    renderers = {f: Renderer(checker_horizon(f), config.horizon_size) for f in TEXTURE_FILTERS}
    camera = CameraFrame.from_spec(renderers["none"].scene.camera)
    for r in renderers.values():
        timed(r, camera, 1, "path", 0)  # compiled here, not in the timings
    reference_renderer = renderers["none"]
    reference_renderer.reset()
    timed(reference_renderer, camera, config.reference_spp, "path", config.reference_seed)
    reference = reference_renderer.image().copy()
    curves = {f: [] for f in TEXTURE_FILTERS}
    for spp in config.horizon_spp:
        for f, r in renderers.items():  # interleaved: one spp count for every filter in turn
            r.reset()
            seconds = timed(r, camera, spp, "path", config.seed + spp)
            curves[f].append({"spp": spp, "seconds": seconds, "rmse": rmse(r.image(), reference)})
    return {"reference_spp": config.reference_spp, "curves": curves}


def speeds(scene_name: str, config: TextureFilterBenchConfig) -> dict:
    """Median samples per second of `mis` at config.size per filter (interleaved rounds)."""
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_named_scene(scene_name)
    renderers = {f: Renderer(replace(scene, render=replace(scene.render, texture_filter=f)), config.size)
                 for f in TEXTURE_FILTERS}
    camera = CameraFrame.from_spec(scene.camera)
    compile_s = {f: timed(r, camera, 1, "mis", 0) for f, r in renderers.items()}
    samples = config.size[0] * config.size[1] * config.speed_spp
    rates = {f: [] for f in TEXTURE_FILTERS}
    for _ in range(config.rounds):
        for f, r in renderers.items():
            r.reset()
            rates[f].append(samples / timed(r, camera, config.speed_spp, "mis", config.seed) / 1e6)
    medians = {f: statistics.median(v) for f, v in rates.items()}
    return {"scene": scene_name, "first_frame_s": compile_s, "msamples_per_s": rates, "median": medians,
            "relative": {f: medians[f] / medians["none"] for f in TEXTURE_FILTERS}}


def denoise_target(config: TextureFilterBenchConfig) -> dict:
    """The textured scene's denoising target at config.size, per filter."""
    from renderer.bench.convergence import noise_floor, progressive
    from renderer.camera import CameraFrame
    from renderer.output.denoise import DenoiseInput, Denoiser, unavailable_reason
    from renderer.renderer import Renderer

    reason = unavailable_reason()
    if reason:
        return {"skipped": reason}
    denoiser = Denoiser()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = load_named_scene("textured")
    camera = CameraFrame.from_spec(scene.camera)
    low, high = config.target_spp
    reference_renderer = Renderer(replace(scene, render=replace(scene.render, texture_filter="none")), config.size)
    timed(reference_renderer, camera, 1, "mis", 0)  # compiled here, not in the reference's seconds
    log(f"[textured] reference at {config.size[0]}x{config.size[1]} for {config.reference_s:g} s ...")
    run = progressive(reference_renderer, camera, "mis", "independent", config.reference_seed, config.reference_s,
                      1 << 24, max_launch_s=3.0)
    reference = reference_renderer.image().copy()
    floor = noise_floor(reference, reference_renderer.film.variance_of_mean_image())["rel_mse"]
    out = {"size": list(config.size), "reference": {"spp": run["spp"], "seconds": run["seconds"],
                                                     "rel_mse_floor": floor}, "filters": {}}
    for f in TEXTURE_FILTERS:
        r = Renderer(replace(scene, render=replace(scene.render, texture_filter=f)), config.size, aovs=True)
        timed(r, camera, 1, "mis", 0)
        r.reset()
        seconds_low = timed(r, camera, low, "mis", config.seed)
        source = DenoiseInput(r.image(), *r.aov_images())
        denoised = denoiser.denoise(source, prefilter_aux=True)
        quick = denoiser.denoise(source, prefilter_aux=False)
        row = {f"seconds_{low}": seconds_low, f"raw_{low}": max(rel_mse(r.image(), reference) - floor, 0.0),
               f"denoised_{low}": max(rel_mse(denoised, reference) - floor, 0.0),
               f"denoised_quick_{low}": max(rel_mse(quick, reference) - floor, 0.0)}
        row[f"seconds_{high}"] = seconds_low + timed(r, camera, high - low, "mis", config.seed)
        row[f"raw_{high}"] = max(rel_mse(r.image(), reference) - floor, 0.0)
        row["passed"] = row[f"denoised_{low}"] < row[f"raw_{high}"]
        out["filters"][f] = row
    return out


def print_report(report: dict, config: TextureFilterBenchConfig) -> None:
    horizon = report.get("horizon", {})
    if "curves" in horizon:
        rows = []
        for f, points in horizon["curves"].items():
            for p in points:
                rows.append([f, p["spp"], f"{p['seconds']:.3f}", f"{p['rmse']:.4f}"])
        print_table(["filter", "spp", "seconds", "RMSE"], rows,
                    f"checker horizon {config.horizon_size[0]}x{config.horizon_size[1]}, path, against "
                    f"{horizon['reference_spp']} spp unfiltered")
    for speed in report.get("speeds", []):
        if "median" in speed:
            print_table(["filter", "M samples/s (median)", "vs none", "first frame s"],
                        [[f, f"{speed['median'][f]:.3f}", f"{speed['relative'][f]:.3f}",
                          f"{speed['first_frame_s'][f]:.1f}"] for f in TEXTURE_FILTERS],
                        f"{speed['scene']} {config.size[0]}x{config.size[1]}, mis, {config.rounds} rounds")
    target = report.get("denoise_target", {})
    if "filters" in target:
        low, high = config.target_spp
        print_table(["filter", f"denoised {low}", f"denoised quick {low}", f"raw {low}", f"raw {high}", "target"],
                    [[f, f"{row[f'denoised_{low}']:.5f}", f"{row[f'denoised_quick_{low}']:.5f}",
                      f"{row[f'raw_{low}']:.5f}", f"{row[f'raw_{high}']:.5f}", "met" if row["passed"] else "missed"]
                     for f, row in target["filters"].items()],
                    f"textured {config.size[0]}x{config.size[1]}: relMSE less the reference's noise "
                    f"({target['reference']['spp']} spp)")


def write_plot(report: dict, out_dir: Path) -> Path | None:
    horizon = report.get("horizon", {})
    if "curves" not in horizon:
        return None
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 4))
    for f, points in horizon["curves"].items():
        ax.loglog([p["seconds"] for p in points], [p["rmse"] for p in points], "o-", label=f)
        for p in points:
            ax.annotate(f"{p['spp']}", (p["seconds"], p["rmse"]), fontsize=7)
    ax.set_xlabel("render seconds")
    ax.set_ylabel("RMSE against the reference")
    ax.set_title("checker horizon: texture filters (labels: spp)")
    ax.legend()
    return save_figure(fig, Path(out_dir) / "bench_texture_filter.png")


def run(quick: bool = False, out_dir: Path = Path("reports"), config: TextureFilterBenchConfig | None = None) -> int:
    import taichi as ti

    from renderer.runtime.arch import init_taichi

    config = config or (QUICK if quick else FULL)
    t_start = time.perf_counter()
    if not ti.lang.impl.get_runtime().prog:
        # Kernels optimised for compile time: ten textured kernels take 6-7 min each to compile
        # with every optimisation (the filters' relative costs are what is measured here).
        init_taichi("cpu", optimize="compile")
    report = {**report_header("texture-filter", quick, load_average(), arch=speed_runtime(), config=asdict(config),
                              optimize="compile")}
    parts = (("horizon", lambda: horizon_curves(config)),
             ("speeds", lambda: [speeds("textured", config), speeds("cornell_box", config)]),
             ("denoise_target", lambda: denoise_target(config)))
    for key, part in parts:
        log(f"texture-filter: {key} ...")
        try:
            report[key] = part()
        except Exception as error:  # noqa: BLE001 - one part must not end the benchmark
            report[key] = {"skipped": describe_error(error)}
    print_report(report, config)
    plot = write_plot(report, out_dir)
    report["plots"] = [plot.name] if plot else []
    report["total_seconds"] = time.perf_counter() - t_start
    path = write_json(Path(out_dir) / "bench_texture_filter.json", report)
    print(f"wrote {path}  (total {report['total_seconds']:.0f} s)")
    return 0 if "curves" in report.get("horizon", {}) else 1

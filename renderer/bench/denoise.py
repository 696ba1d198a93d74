"""`python app.py bench denoise`: what denoising and adaptive sampling buy, against a long reference.

For each scene (cornell_box, bunnies, studio, showcase, textured), in one process, with `mis`:

1. Compile (1 spp, reported), then a reference: `mis` on its own seed for `reference_s` seconds.
   Every error is also given floor-corrected (relMSE minus the reference's own noise, an
   unbiased estimate of the error against the true image, the two renders being independent).
2. Raw and denoised against spp: totals of 1, 2, 4, ... max_spp samples per pixel; after each, the
   raw image and Open Image Denoise's output are compared with the reference, in both of
   renderer/output/denoise.py's forms: `denoised` (the AOVs prefiltered, what `render --denoise` writes
   and the viewer's later denoises show) and `denoised_quick` (the noisy AOVs passed straight in:
   the viewer's first denoise of an accumulation). Render time is cumulative and excludes the
   denoiser, whose time is its own column.
   Derived: the spp at which raw reaches the error of denoised-at-8-spp (log-log interpolation,
   extrapolated as relMSE ~ 1/spp past the last point and flagged).
3. Adaptive against uniform sampling at equal time: the time uniform sampling took for
   `equal_time_spp` spp (256: with min spp 16 and a stop confirmed at the next doubling, nothing
   stops before 32 spp, so a budget of 64 left the rule a quarter of it) is the budget; a uniform
   render and adaptive renders (renderer/film/adaptive.py) with each threshold of `thresholds` run in
   growing passes until that budget, and are compared at the budget. They take turns pass by pass
   (race(): each film is kept aside between its turns), so a change of the machine's speed hits
   all of them alike; run one after the other, that decided the verdicts. An adaptive render
   that stops every pixel before the budget has taken less time: it is compared with the uniform
   render as it was at about that time instead (the table says "ended early").
   All use the same seed, so a pixel's first samples are the same in both, and the
   difference of their errors is tested per pixel (common.error_difference: mean difference, its
   standard error over the pixels, z; |z| > common.Z_SIGNIFICANT is a difference at the 5% level, two-
   sided), untrimmed and without the 0.1% of pixels with the largest errors: at these sample counts
   a handful of fireflies decide the untrimmed relMSE of bunnies, studio and showcase (0.05-0.45).
4. The denoising target again at the viewer's size, 960x540 (viewer_size_target()): a reference
   of its own (`viewer_reference_s`), raw and denoised at 8 spp without the AOVs' feature samples
   and with them (renderer/film/aovs.py), and raw at 128 spp.
5. The denoiser's time for one 960x540 frame in each form (median of 3, after one warm-up call).

The curves are 320x180: the denoiser's error depends on how many pixels a feature spans, and at
160x90 (the size before) a floor tile or a texture's checker is a few pixels wide, unlike the
viewer's 960x540 (measured on textured, AOVs prefiltered, 8 spp against raw at 128: 0.0084 vs
0.0021 at 160x90, 0.0056 vs 0.0018 at 320x180, 0.0028 vs 0.0016 at 640x360). Curves and races at
960x540 would take a whole afternoon; the target alone there took 926 s of a 1,830 s run.

Targets (the issue's): denoised at 8 spp below raw at 128 spp in relMSE on each scene, judged at
the viewer's 960x540 (the 320x180 verdicts are printed too); adaptive (at the default threshold,
DEFAULT_THRESHOLD, chosen before measuring) below uniform at equal time on at least four of the
five scenes. Every render here keeps the AOVs, so the curves' seconds for textured include its
feature samples over its first 8 spp (the colour is the same with or without them).

textured is the hard case. Its denoised error lies on the floor's thin grid lines (73% of it) and
the sphere's tile bevels (26%): sub-pixel detail whose coverage 8 samples estimate noisily, in
the AOVs as in the colour.
Measured on it (ad hoc probes, 320x180, 8 spp, relMSE less the reference's noise): the AOVs
passed noisy 0.0078; prefiltered (the default) 0.0056; AOVs of 256 spp passed as clean 0.0028,
the denoiser's own limit here, against raw 0.0018 at 128 spp; albedo demodulation (the colour
over the albedo denoised, then times an albedo) 0.0037 with the 256-spp albedo, 0.0069 with the
prefiltered one; the Sobol sampler brings denoised 8 spp to 0.0029 but raw 128 spp to 0.0006.
At the viewer's 960x540 (a reference of 600 s, 2,888 spp): denoised 0.00171 against raw 0.00145;
with AOVs of 40 spp 0.00130, of 288 spp 0.00114. Hence the feature samples (40 AOV samples at 8
spp, in scenes with textures) and the target at 960x540, where textured passes; at 320x180 it
still misses, even with AOVs of 256 spp.

Writes <out_dir>/bench_denoise.json and one log-log plot per scene.
"""
from __future__ import annotations

import statistics
import time
import warnings
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from renderer.bench.common import (describe_error, error_difference, load_average, load_named_scene, log, paired_text,
                                   paired_verdict, print_table, pyplot, rel_mse, report_header, save_figure, speed_runtime,
                                   verdict, write_json)
from renderer.bench.convergence import FIREFLY_TRIM, noise_floor, progressive, spp_to_reach, sync

INTEGRATOR = "mis"
DEFAULT_THRESHOLD = 0.05
# An adaptive render that stopped every pixel before this share of the budget ended early (the
# passes' last one may end a little before the budget without that).
EARLY_END = 0.95
PASS_S = 0.5  # the longest pass of an equal-time race (shorter: the contestants alternate more often)


@dataclass(frozen=True)
class DenoiseBenchConfig:
    size: tuple[int, int] = (320, 180)
    reference_s: float = 120.0
    reference_launch_s: float = 3.0
    max_spp: int = 256
    equal_time_spp: int = 256
    thresholds: tuple[float, ...] = (0.02, DEFAULT_THRESHOLD, 0.1)
    min_spp: int = 16
    seed: int = 1
    reference_seed: int = 7919
    frame_size: tuple[int, int] = (960, 540)
    scenes: tuple[str, ...] = ("cornell_box", "bunnies", "studio", "showcase", "textured")
    # The denoising target again at the viewer's size (None: not measured): raw and denoised at 8
    # spp and raw at 128 against a reference of `viewer_reference_s`.
    viewer_size: tuple[int, int] | None = (960, 540)
    viewer_reference_s: float = 120.0


FULL = DenoiseBenchConfig()
QUICK = DenoiseBenchConfig(size=(64, 36), reference_s=8.0, reference_launch_s=1.0, max_spp=32, equal_time_spp=16,
                           thresholds=(DEFAULT_THRESHOLD,), min_spp=4, frame_size=(320, 180), viewer_size=(128, 72),
                           viewer_reference_s=8.0)
TARGET_SPP = (8, 128)  # the target: denoised at 8 spp below raw at 128


def denoise_curve(renderer, camera, denoiser, reference, floor, config: DenoiseBenchConfig) -> list[dict]:
    """Raw and denoised relMSE at 1, 2, 4, ... max_spp spp (cumulative render seconds)."""
    from renderer.output.denoise import DenoiseInput

    renderer.reset()
    points, seconds, done = [], 0.0, 0
    while done < config.max_spp:
        n = max(1, done)
        t0 = time.perf_counter()
        renderer.render(camera, n, INTEGRATOR, seed=config.seed)
        sync()
        seconds += time.perf_counter() - t0
        done += n
        raw = renderer.image()
        albedo, normal = renderer.aov_images()
        source = DenoiseInput(raw, albedo, normal)
        t0 = time.perf_counter()
        denoised = denoiser.denoise(source, prefilter_aux=True)
        denoise_s = time.perf_counter() - t0
        quick = denoiser.denoise(source, prefilter_aux=False)
        raw_error, denoised_error, quick_error = (rel_mse(x, reference) for x in (raw, denoised, quick))
        points.append({"spp": done, "seconds": seconds, "denoise_s": denoise_s, "raw": raw_error,
                       "denoised": denoised_error, "raw_corrected": max(raw_error - floor, 0.0),
                       "denoised_corrected": max(denoised_error - floor, 0.0),
                       "denoised_quick_corrected": max(quick_error - floor, 0.0)})
    return points


@dataclass
class Contestant:
    """One render of an equal-time comparison: uniform sampling (threshold None) or adaptive."""

    threshold: float | None
    budget_s: float
    state: object = None  # the film between its turns (Renderer.state()); None: not started
    slices_done: int = 0
    seconds: float = 0.0
    pass_slices: int = 1
    pixels_active: int = 0
    # With keep_turns, the film after each turn: (seconds, state, slices_done, pixels_active).
    keep_turns: bool = False
    turns: list = field(default_factory=list)

    @property
    def finished(self) -> bool:
        return self.state is not None and (self.seconds >= self.budget_s or self.pixels_active == 0)

    def at(self, seconds: float) -> "Contestant":
        """The contestant as it was after the kept turn that ended nearest `seconds`."""
        when, state, slices_done, active = min(self.turns, key=lambda turn: abs(turn[0] - seconds))
        return replace(self, state=state, slices_done=slices_done, seconds=when, pixels_active=active,
                       keep_turns=False, turns=[])


def take_turn(renderer, camera, contestant: Contestant, config: DenoiseBenchConfig) -> None:
    """Load the contestant's film, render one timed pass (growing to at most PASS_S seconds and
    ending at its budget), keep the film."""
    from renderer.renderer import AdaptiveSettings

    if contestant.state is None:
        renderer.reset()
    else:
        renderer.restore(contestant.state, contestant.slices_done)
    threshold = contestant.threshold
    renderer.set_adaptive(None if threshold is None else AdaptiveSettings(threshold, config.min_spp))
    try:
        before = renderer.slices_done
        t0 = time.perf_counter()
        renderer.render_slices(camera, contestant.pass_slices, INTEGRATOR, seed=config.seed)
        sync()
        dt = time.perf_counter() - t0
    finally:
        renderer.set_adaptive(None)
    contestant.seconds += dt
    rate = max(dt / max(renderer.slices_done - before, 1), 1e-9)
    left = contestant.budget_s - contestant.seconds
    contestant.pass_slices = max(1, min(4 * contestant.pass_slices, int(left / rate) + 1, int(PASS_S / rate)))
    contestant.state, contestant.slices_done = renderer.state(), renderer.slices_done
    contestant.pixels_active = renderer.pixels_active
    if contestant.keep_turns:
        contestant.turns.append((contestant.seconds, contestant.state, contestant.slices_done,
                                 contestant.pixels_active))


def race(renderer, camera, contestants: list[Contestant], config: DenoiseBenchConfig) -> None:
    """Render every contestant from an empty film to its budget, taking turns pass by pass: a
    change of the machine's speed meanwhile (other load, clocks) hits them all alike. One after
    the other, the machine decided the verdicts: the same rule at the same threshold was better
    than uniform by z -13 in one run and worse by z +26 in the next (Cornell box, 0.05)."""
    while not all(c.finished for c in contestants):
        for contestant in contestants:
            if not contestant.finished:
                take_turn(renderer, camera, contestant, config)


def contestant_result(renderer, contestant: Contestant, reference, floor) -> tuple[dict, np.ndarray]:
    """(the figures, the image) of a finished contestant."""
    renderer.restore(contestant.state, contestant.slices_done)
    counts = renderer.film.sample_counts() + renderer.film.rejected_counts()
    image = renderer.image()
    error = rel_mse(image, reference)
    result = {"threshold": contestant.threshold, "seconds": contestant.seconds, "max_spp": renderer.mean_spp,
              "mean_spp": float(counts.mean()), "stopped_fraction": 1.0 - contestant.pixels_active / counts.size,
              "rel_mse": error, "rel_mse_corrected": max(error - floor, 0.0)}
    return result, image


def uniform_summary(uniform: dict) -> dict:
    return {"spp": uniform["max_spp"], "seconds": uniform["seconds"], "rel_mse": uniform["rel_mse"],
            "rel_mse_corrected": uniform["rel_mse_corrected"]}


def at_equal_time(renderer, camera, reference, floor, budget_s: float, config: DenoiseBenchConfig
                  ) -> tuple[dict, list[dict]]:
    """Uniform sampling and adaptive sampling at each of config.thresholds, raced (race()) for
    `budget_s` seconds each from the same seed. Returns (the uniform render's figures, the adaptive
    renders' figures with their paired comparison against uniform).

    An adaptive render whose every pixel met the threshold before the budget ended there, having
    taken less time: it is compared with the uniform render as it was at about that time (its
    film after the turn that ended nearest; turns last at most PASS_S), since at the budget it
    had more time. Each adaptive render's figures carry the uniform render they were compared
    with (`uniform`) and whether it ended early."""
    uniform = Contestant(None, budget_s, keep_turns=True)
    adaptive = [Contestant(threshold, budget_s) for threshold in config.thresholds]
    race(renderer, camera, [uniform, *adaptive], config)
    uniform_figures, uniform_image = contestant_result(renderer, uniform, reference, floor)
    results = []
    for contestant in adaptive:
        figures, image = contestant_result(renderer, contestant, reference, floor)
        compared, compared_image = uniform_figures, uniform_image
        figures["ended_early"] = contestant.pixels_active == 0 and contestant.seconds < EARLY_END * budget_s
        if figures["ended_early"]:
            compared, compared_image = contestant_result(renderer, uniform.at(contestant.seconds), reference, floor)
        figures["uniform"] = uniform_summary(compared)
        figures["paired"] = error_difference(image, compared_image, reference, "rel_mse").as_dict()
        figures["paired_trimmed"] = error_difference(image, compared_image, reference, "rel_mse",
                                                     trim=FIREFLY_TRIM).as_dict()
        results.append(figures)
    return uniform_figures, results


def denoiser_frame_time(denoiser, scene, size, prefilter_aux: bool = True) -> float:
    """Median seconds of denoising one frame of `scene` at `size` (1 spp with AOVs)."""
    from renderer.camera import CameraFrame
    from renderer.output.denoise import DenoiseInput
    from renderer.renderer import Renderer

    renderer = Renderer(scene, size, aovs=True)
    renderer.render(CameraFrame.from_spec(scene.camera), 1, INTEGRATOR)
    source = DenoiseInput(renderer.image(), *renderer.aov_images())
    denoiser.denoise(source, prefilter_aux=prefilter_aux)
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        denoiser.denoise(source, prefilter_aux=prefilter_aux)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def reference_render(renderer, camera, scene_name: str, seconds: float, config: DenoiseBenchConfig) -> tuple:
    """(reference image, its relMSE noise floor, its summary): `mis` on the reference seed for
    `seconds` of render time."""
    size = f"{renderer.film.width}x{renderer.film.height}"
    log(f"[{scene_name}] reference at {size} for {seconds:g} s ...")
    run = progressive(renderer, camera, INTEGRATOR, "independent", config.reference_seed, seconds, 1 << 24,
                      max_launch_s=config.reference_launch_s)
    reference = renderer.image()
    floor = noise_floor(reference, renderer.film.variance_of_mean_image())["rel_mse"]
    return reference, floor, {"spp": run["spp"], "seconds": run["seconds"], "rel_mse_floor": floor}


def timed_render(renderer, camera, spp: int, seed: int) -> float:
    t0 = time.perf_counter()
    renderer.render(camera, spp, INTEGRATOR, seed=seed)
    sync()
    return time.perf_counter() - t0


def viewer_size_target(scene, denoiser, config: DenoiseBenchConfig) -> dict:
    """The denoising target at the viewer's size, where a texture's lines and a normal map's bevels
    span more pixels than at the curves' size: raw and denoised (AOVs prefiltered) at 8 spp, and
    raw at 128 spp, against a reference of config.viewer_reference_s. The 8 spp are rendered
    without the AOVs' feature samples and with DEFAULT_FEATURE_BOOST of them (renderer/film/aovs.py);
    `denoised_8` and `seconds_8` are those of the scene's own choice (`feature_boost`), what
    `render --denoise` does. Times are render seconds (the denoiser's excluded)."""
    from renderer.film.aovs import DEFAULT_FEATURE_BOOST
    from renderer.camera import CameraFrame
    from renderer.output.denoise import DenoiseInput
    from renderer.renderer import Renderer

    low, high = TARGET_SPP
    renderer = Renderer(scene, config.viewer_size, aovs=True)
    camera = CameraFrame.from_spec(scene.camera)
    timed_render(renderer, camera, 1, 0)  # compiled here (the curves' renderer is another instance)
    reference, floor, summary = reference_render(renderer, camera, scene.name, config.viewer_reference_s, config)
    boost = renderer.scene_feature_boost
    out = {"size": list(config.viewer_size), "reference": summary, "feature_boost": boost,
           "with_features_boost": DEFAULT_FEATURE_BOOST}
    for label, features in (("without_features", 0), ("with_features", DEFAULT_FEATURE_BOOST)):
        renderer.feature_boost = features
        renderer.reset()
        seconds = timed_render(renderer, camera, low, config.seed)
        denoised = denoiser.denoise(DenoiseInput(renderer.image(), *renderer.aov_images()), prefilter_aux=True)
        out[f"seconds_{low}_{label}"] = seconds
        out[f"denoised_{low}_{label}"] = max(rel_mse(denoised, reference) - floor, 0.0)
    renderer.feature_boost = boost
    chosen = "with_features" if boost else "without_features"
    out[f"seconds_{low}"], out[f"denoised_{low}"] = out[f"seconds_{low}_{chosen}"], out[f"denoised_{low}_{chosen}"]
    out[f"raw_{low}"] = max(rel_mse(renderer.image(), reference) - floor, 0.0)
    log(f"[{scene.name}] raw to {high} spp at the viewer's size ...")
    # (the colour goes on from the 8 spp just rendered: feature samples never change it)
    out[f"seconds_{high}"] = out[f"seconds_{low}"] + timed_render(renderer, camera, high - low, config.seed)
    out[f"raw_{high}"] = max(rel_mse(renderer.image(), reference) - floor, 0.0)
    out["passed"] = out[f"denoised_{low}"] < out[f"raw_{high}"]
    return out


def bench_scene(scene, denoiser, config: DenoiseBenchConfig) -> dict:
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    renderer = Renderer(scene, config.size, aovs=True)
    camera = CameraFrame.from_spec(scene.camera)
    compile_s = timed_render(renderer, camera, 1, 0)
    result = {"scene": scene.name, "size": list(config.size), "compile_s": compile_s}
    log(f"[{scene.name}] first launch {compile_s:.1f} s")
    reference, floor, result["reference"] = reference_render(renderer, camera, scene.name, config.reference_s, config)

    log(f"[{scene.name}] raw and denoised to {config.max_spp} spp ...")
    points = denoise_curve(renderer, camera, denoiser, reference, floor, config)
    result["curve"] = points
    by_spp = {p["spp"]: p for p in points}
    at8 = by_spp.get(8) or points[min(3, len(points) - 1)]
    reach, extrapolated = spp_to_reach(points, "raw_corrected", max(at8["denoised_corrected"], 1e-12), power=1.0)
    result["raw_spp_matching_denoised_8"] = {"spp": reach, "extrapolated": extrapolated}
    raw128 = by_spp.get(128) or points[-1]
    result["target_denoise"] = {"denoised_8": at8["denoised_corrected"], "raw_128": raw128["raw_corrected"],
                                "raw_spp": raw128["spp"], "passed": at8["denoised_corrected"] < raw128["raw_corrected"]}

    # Equal time: the budget is what uniform sampling took for equal_time_spp in the curve; the
    # uniform render compared is made again, raced against the adaptive ones (at_equal_time), so
    # all pay the same kind of passes and see the same machine.
    budget = (by_spp.get(config.equal_time_spp) or points[-1])["seconds"]
    log(f"[{scene.name}] uniform and adaptive at equal time, {budget:.1f} s each ...")
    uniform, result["adaptive"] = at_equal_time(renderer, camera, reference, floor, budget, config)
    result["uniform"] = uniform_summary(uniform)
    default = next((a for a in result["adaptive"] if a["threshold"] == DEFAULT_THRESHOLD), result["adaptive"][0])
    compared = default["uniform"]["rel_mse_corrected"]
    result["target_adaptive"] = {"threshold": default["threshold"], "adaptive": default["rel_mse_corrected"],
                                 "uniform": compared, "passed": default["rel_mse_corrected"] < compared,
                                 "paired": paired_verdict(default.get("paired")),
                                 "paired_trimmed": paired_verdict(default.get("paired_trimmed"))}
    if config.viewer_size is not None:
        result["viewer_size"] = viewer_size_target(scene, denoiser, config)
    return result


def run(quick: bool = False, out_dir: Path = Path("reports"), scenes=None, config: DenoiseBenchConfig | None = None) -> int:
    from renderer.output.denoise import Denoiser, unavailable_reason

    reason = unavailable_reason()
    if reason:
        print(f"bench denoise: {reason}")
        return 1
    config = config or (QUICK if quick else FULL)
    if scenes is not None:
        config = replace(config, scenes=tuple(str(s) for s in scenes))
    t_start = time.perf_counter()
    arch = speed_runtime()
    load_before = load_average()
    denoiser = Denoiser()
    try:
        first = load_named_scene(config.scenes[0])
        frame_s = denoiser_frame_time(denoiser, first, config.frame_size)
        frame_quick_s = denoiser_frame_time(denoiser, first, config.frame_size, prefilter_aux=False)
    except Exception as error:  # noqa: BLE001 - the curves are worth having without it
        log(f"denoiser frame time: {describe_error(error)}")
        frame_s = frame_quick_s = float("nan")
    results = []
    for name in config.scenes:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                scene = load_named_scene(name)
            results.append(bench_scene(scene, denoiser, config))
        except Exception as error:  # noqa: BLE001 - one scene must not end the benchmark
            results.append({"scene": Path(name).stem, "skipped": describe_error(error)})
    print_report(results, config, frame_s, frame_quick_s)
    plots = write_plots(results, out_dir)
    report = {**report_header("denoise", quick, load_before, arch=arch, config=asdict(config)),
              "denoiser_frame_s": frame_s, "denoiser_frame_quick_s": frame_quick_s,
              "frame_size": list(config.frame_size), "scenes": results,
              "plots": [p.name for p in plots], "total_seconds": time.perf_counter() - t_start}
    path = write_json(Path(out_dir) / "bench_denoise.json", report)
    print(f"wrote {path}  (total {report['total_seconds']:.0f} s)")
    return 0 if any("curve" in r for r in results) else 1


def print_report(results: list[dict], config: DenoiseBenchConfig, frame_s: float, frame_quick_s: float) -> None:
    done = [r for r in results if "curve" in r]
    for res in results:
        if "skipped" in res:
            print(f"{res['scene']}: skipped ({res['skipped']})\n")
    rows = []
    for res in done:
        for p in res["curve"]:
            rows.append([res["scene"], p["spp"], p["seconds"], p["raw_corrected"], p["denoised_corrected"],
                         p.get("denoised_quick_corrected", float("nan")), p["denoise_s"]])
    w, h = config.size
    print_table(["scene", "spp", "render s", "raw relMSE", "denoised relMSE", "quick denoised relMSE", "denoise s"],
                rows,
                title=f"Raw and denoised against a long reference ({INTEGRATOR}, {w}x{h}; relMSE minus the "
                      "reference's noise)")
    rows = []
    for res in done:
        t, m = res["target_denoise"], res["raw_spp_matching_denoised_8"]
        rows.append([res["scene"], res["reference"]["spp"], t["denoised_8"], t["raw_128"],
                     f"{m['spp']:.0f}{' (extrapolated)' if m['extrapolated'] else ''}", verdict(t["passed"])])
    print_table(["scene", "reference spp", "denoised @8", f"raw @{config.max_spp if config.max_spp < 128 else 128}",
                 "raw spp to match denoised @8", "denoised @8 < raw @128"], rows, title=f"Denoising at {w}x{h}")
    viewer = [r for r in done if "viewer_size" in r]
    if viewer:
        vw, vh = viewer[0]["viewer_size"]["size"]
        print_table(["scene", "reference spp", "raw @8", "feature samples", "denoised @8, none",
                     "denoised @8, with", "raw @128", "render s @8, none", "@8, with", "@128",
                     "denoised @8 < raw @128"],
                    [viewer_row(r) for r in viewer],
                    title=f"Denoising at the viewer's size, {vw}x{vh} (AOVs prefiltered; relMSE minus the "
                          "reference's noise; the target takes the scene's own choice of feature samples, "
                          "the second column)")
    rows = []
    for res in done:
        for a in res["adaptive"]:
            u = a.get("uniform", res["uniform"])
            rows.append([res["scene"], f"{u['seconds']:.3g}{' (ended early)' if a.get('ended_early') else ''}",
                         u["spp"], u["rel_mse_corrected"], a["threshold"], a["mean_spp"],
                         a["stopped_fraction"], a["rel_mse_corrected"],
                         verdict(a["rel_mse_corrected"] < u["rel_mse_corrected"]), paired_text(a.get("paired")),
                         paired_text(a.get("paired_trimmed"))])
    print_table(["scene", "equal time s", "uniform spp", "uniform relMSE", "threshold", "adaptive mean spp", "stopped",
                 "adaptive relMSE", "adaptive better", "paired z", "paired z, trimmed"], rows,
                title="Adaptive against uniform sampling at equal time (the budget, or the adaptive render's own "
                      "time where it stopped every pixel before it)")
    wins = sum(r["target_adaptive"]["passed"] for r in done)
    print(f"Target: adaptive (threshold {DEFAULT_THRESHOLD:g}) below uniform at equal time on >= 4 of 5 scenes: "
          f"{wins} of {len(done)}  {verdict(wins >= 4)}")
    for key, label in (("paired", "all pixels"), ("paired_trimmed", "without the 0.1% largest errors")):
        verdicts = [r["target_adaptive"].get(key, "n/a") for r in done]
        print(f"  paired z-test at the 5% level ({label}): better on {verdicts.count('better')}, "
              f"worse on {verdicts.count('worse')}, no significant difference on {verdicts.count('tie')}")
    passed = all(r["target_denoise"]["passed"] for r in done) and done
    print(f"Target: denoised at 8 spp below raw at 128 spp on every scene, at {w}x{h}: {verdict(bool(passed))}")
    if viewer:
        passed = all(r["viewer_size"]["passed"] for r in viewer) and len(viewer) == len(done)
        print(f"Target: denoised at 8 spp below raw at 128 spp on every scene, at the viewer's {vw}x{vh}: "
              f"{verdict(bool(passed))}")
    w, h = config.frame_size
    print(f"Denoiser time per {w}x{h} frame: {frame_s * 1000:.0f} ms with the AOVs prefiltered, "
          f"{frame_quick_s * 1000:.0f} ms quick (median of 3)\n")


def viewer_row(result: dict) -> list:
    """A scene's row of the table of the target at the viewer's size (printed and on the page)."""
    v = result["viewer_size"]
    return [result["scene"], v["reference"]["spp"], v["raw_8"], f"{v['feature_boost']} each" if v["feature_boost"] else "none",
            v["denoised_8_without_features"], v["denoised_8_with_features"], v["raw_128"],
            v["seconds_8_without_features"], v["seconds_8_with_features"], v["seconds_128"], verdict(v["passed"])]


def write_plots(results: list[dict], out_dir: Path) -> list[Path]:
    plt = pyplot()
    paths = []
    for res in results:
        if "curve" not in res:
            continue
        fig, ax = plt.subplots(figsize=(6, 4))
        pts = res["curve"]
        for key, label in (("raw_corrected", "raw"), ("denoised_corrected", "denoised"),
                           ("denoised_quick_corrected", "denoised, quick")):
            if all(key in p for p in pts):
                ax.loglog([p["seconds"] for p in pts], [max(p[key], 1e-9) for p in pts], marker="o", label=label)
        for a in res["adaptive"]:
            ax.scatter([a["seconds"]], [max(a["rel_mse_corrected"], 1e-9)], marker="x",
                       label=f"adaptive {a['threshold']:g}")
        ax.set_xlabel("render seconds")
        ax.set_ylabel("relMSE (minus reference noise)")
        ax.set_title(f"{res['scene']}: raw vs denoised, adaptive at equal time")
        ax.legend(fontsize=8)
        paths.append(save_figure(fig, Path(out_dir) / f"bench_denoise_{res['scene']}.png"))
    return paths

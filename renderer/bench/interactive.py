"""`python app.py bench interactive`: does the viewer answer every input within a frame?

It drives the real viewer (viewer.window.ViewerApp, an off-screen GGUI window: the same frame
loop, tone mapping, HUD and canvas upload as on screen) through every chosen scene and
integrator, at 960x540 by default:

  switch     load the scene (the first visit builds its Renderer), select the integrator and
             step until the first rendered image: load, compile (the render call of the frame
             that compiles, after the frame that shows the "compiling..." notice) and
             first-image time of that switch, and the longest frame meanwhile. Taichi's offline
             cache is warm after the first run, so the compile is mostly the kernels' warm start.
  still      Still frames without input: frame times, presents, and the samples per second of
             those time-sliced frames (an untouched still view presents about once a second and
             otherwise only renders: viewer/session.py), in RATE_ROUNDS pairs of blocks with
             still frames made of whole samples per pixel (the viewer before pixel slices), in
             the same frame loop: a block of whole-sample frames (STILL_SECONDS / RATE_ROUNDS,
             at least one frame: seconds each on a slow scene), then sliced frames for as long
             as it took (paired_rate_blocks; each kind's blocks go on with its own present
             clocks, so each redraws as a continuous still view of its kind). The sliced rate
             must stay within 5% of it: the median over the pairs of sliced / whole samples
             per second.
             The blocks start after the view's first full-resolution round, which is rendered
             first, in sliced frames, and reported on its own ("first round"): its slices are
             interleaved (a coarse-to-fine image: renderer/film/pixel_slices.py), which costs more
             per sample than the rows of the rounds after it (ad hoc, 960x540 on a quiet 2-core
             machine, first round / steady state against whole-sample frames, when a whole
             round was in Bayer order: cornell_box/mis 0.80 / 1.00, foggy/nee 0.92 / 0.95,
             showcase/mis 0.91 / 0.97; its last three quarters now go by rows of each cell), and
             a still view spends its first 0.1-2 s there, so blocks that began with it measured
             mostly it.
             Then ANSWER_SECONDS of still frames every third of which gets a key press (Tab
             toggles the help overlay, a display-only change, and the benchmark checks that the
             same frame presented it), for each of the two: the times of frames that answer an
             input (the whole-sample frames' latency is the "before" figure).
  moving     MOVING_SECONDS with W held (the camera flies): frame times (every one presents).

Latency is measured from an input event to the end of the first frame that shows its effect.
GGUI queues events while a frame renders and the next frame reads them first, so an event that
arrives at a uniformly random moment waits for the rest of the frame it arrived in and shows at
the end of the frame after it: latency = (1 - u) * t_k + t_answer, with frame k drawn in
proportion to its length (a long frame catches more events), u uniform, and t_answer the next
moving frame, or one of the measured frames that answered a key while still (fixed seed). All
are measured wall times of the real loop.

Target (issue: "Interactive on a CPU"): p95 latency at most 100 ms for every scene and
integrator, still or moving, on a quiet machine; still samples/s at least 95% of whole-image
passes. GGUI's own frame (software Vulkan: the canvas image and the HUD drawn, then read back
off-screen or presented) takes ~10-15 ms whatever the viewer does, which is why the still view
presents only on input and a few times a second. Writes <out_dir>/bench_interactive.json and
bench_interactive.png; with --packets N the viewer traces N rays a packet where a scene allows
(`view --packets N`), and the files are bench_interactive_packetsN.*: the moving frames' film
size, at the same frame budget, is what packets buy the moving view.
"""
from __future__ import annotations

import math
import random
import statistics
import tempfile
import time
import warnings
from pathlib import Path
from typing import Optional

from renderer.bench.common import (describe_error, load_average, log, print_table, pyplot, report_header,
                                   save_figure, verdict, write_json)
from renderer.film.pixel_slices import ROUND_SLICES

DEFAULT_SIZE = (960, 540)
TARGET_LATENCY_MS = 100.0
TARGET_STILL_RATE = 0.95  # sliced still frames keep this share of whole-image passes' samples/s
STILL_SECONDS = 12.0  # untouched: RATE_ROUNDS pairs of blocks, each of at least its share of it
ANSWER_SECONDS = 1.5  # still frames answering keys, for each of the two kinds
MOVING_SECONDS = 2.0
SWITCH_FRAMES_LIMIT = 50  # a switch that has not shown an image after this many frames failed
EVENTS = 2000  # simulated input events per measured phase (their arrival moments; see event_latencies)
KEY_EVERY = 3  # still frames per key press while measuring the frames that answer an input
# Pairs of blocks of whole-sample and sliced still frames: on this shared 2-core machine one
# pair's ratio moved 0.76-1.33 with blocks of 2 s (a full run, three pairs), and 0.92-1.05 with
# blocks of 1.2 s in the runs of 2026-12-05, where a view's median of five pairs (standard error
# ~1.4%) decided its verdict at 0.95 against a mean loss of 1.5%: so the median of ten.
RATE_ROUNDS = 10
FIRST_ROUND_LIMIT_S = 20.0  # longest wait for a view's first round (sppm: its first iteration)
FULL_INTEGRATORS = ("path", "nee", "mis", "sppm", "normals")
QUICK = {"scenes": ("cornell_box", "showcase"), "integrators": ("path", "mis"), "size": (320, 180),
         "still_seconds": 1.0, "answer_seconds": 0.5, "moving_seconds": 0.7}


def viewer_runtime() -> str:
    """Taichi as `app.py view` starts it (CPU, kernels optimised for compile time: what a user
    waits for on a switch), unless the caller has initialised it already; the back-end's name."""
    import taichi as ti

    from renderer.runtime.arch import init_taichi

    if not ti.lang.impl.get_runtime().prog:
        init_taichi("cpu", optimize="compile")
    return str(ti.lang.impl.current_cfg().arch).split(".")[-1]


def percentile(values, q: float) -> float:
    """The q-quantile (0..1) by linear interpolation between order statistics."""
    ordered = sorted(values)
    if not ordered:
        return math.nan
    position = q * (len(ordered) - 1)
    low = math.floor(position)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (position - low) * (ordered[high] - ordered[low])


def event_latencies(frame_seconds: list[float], rng: random.Random, answers: Optional[list[float]] = None,
                    count: int = EVENTS) -> list[float]:
    """`count` events at uniformly random moments of the measured frames (a frame is hit in
    proportion to its length), each shown at the end of the frame after the one it arrived in:
    the next measured frame, or with `answers` one of those frame times (the frames that
    answered an input). See the module docstring."""
    hit = frame_seconds if answers is not None else frame_seconds[:-1]
    if not hit or (answers is not None and not answers):
        return []
    latencies = []
    for k in rng.choices(range(len(hit)), weights=hit, k=count):
        after = frame_seconds[k + 1] if answers is None else rng.choice(answers)
        latencies.append((1.0 - rng.random()) * hit[k] + after)
    return latencies


def _step_timed(app, inp) -> float:
    t0 = time.perf_counter()
    app.step(inp)
    return time.perf_counter() - t0


def measure_switch(app, scene_path: Path, integrator: str) -> dict:
    """Select scene and integrator; step until a rendered image shows. Frames that only show the
    'compiling' notice are counted: they are what the user sees meanwhile. compile_s is the
    render call of the frame that compiled (None: nothing to compile, the kernels were built
    earlier in this process)."""
    from viewer.cache_warmer import step_to_first_image

    t0 = time.perf_counter()
    app.select_scene(scene_path)
    app.session.set_integrator(integrator)
    app.session.reset_camera()  # the scene's own view: the last combination's flight moved it
    load_s = time.perf_counter() - t0
    app.compile_seconds = None
    shown = step_to_first_image(app, SWITCH_FRAMES_LIMIT)
    return {"load_s": load_s, "compile_s": app.compile_seconds, "first_image_s": time.perf_counter() - t0,
            "frames": shown["frames"], "notice_frames": shown["notice_frames"],
            "longest_frame_s": shown["longest_frame_s"]}


def settle_still(app) -> bool:
    """Step to the first frame that accumulates at full size (the frames before it are the
    switch's preview and reset); whether one came within SWITCH_FRAMES_LIMIT frames."""
    from viewer.window import FrameInput

    for _ in range(SWITCH_FRAMES_LIMIT):
        if app.last_plan is not None and not app.last_plan.interactive and not app.last_plan.reset:
            return True
        app.step(FrameInput())
    return False


def _still_step(app, inp) -> tuple[float, float]:
    """(seconds, pixel samples) of one still frame."""
    slices_before = app.renderer.slices_done
    seconds = _step_timed(app, inp)
    if app.last_plan.reset:
        raise RuntimeError("a still frame reset the accumulation")
    film = app.renderer.film
    return seconds, (app.renderer.slices_done - slices_before) * film.width * film.height / ROUND_SLICES


def still_frames_while(app, go_on) -> dict:
    """Still frames without input while `go_on(times)` holds (times: those of the frames so far):
    their times, pixel samples and presents."""
    from viewer.window import FrameInput

    times, samples, presents = [], 0.0, app.presents
    while go_on(times):
        taken, added = _still_step(app, FrameInput())
        times.append(taken)
        samples += added
    return {"times": times, "pixel_samples": samples, "presents": app.presents - presents}


def untouched_frames(app, seconds: float, min_frames: int = 3) -> dict:
    """Still frames without input for `seconds` of frame time (at least `min_frames` frames)."""
    return still_frames_while(app, lambda times: sum(times) < seconds or len(times) < min_frames)


def paired_rate_blocks(app, seconds: float, rounds: int = RATE_ROUNDS) -> dict[int, list[dict]]:
    """`rounds` pairs of untouched still blocks, {fewest slices a frame: blocks}: whole-sample
    frames (min_still_slices a round) for `seconds` (at least one frame: a slow scene's take
    seconds each), then the viewer's sliced frames for as long as that block took. Equal times
    make a drift of the machine's speed hit both alike, and neither kind's block is mostly its
    start (the first frame after the other kind presents: the still view's redraw was due).
    Each block resumes its kind's present and statistics clocks where that kind's last block
    left them (ViewerApp.resume_still_clocks; the first of each kind starts with both due), so
    each kind redraws as a continuous untouched still view of its own does: once a present
    interval (about 1 s), a whole-sample frame at most once. Clocks shared by the two kinds made
    a slow scene's whole-sample block of one frame, begun within a present interval of the
    sliced block's last redraw, never present (showcase / mis: 0 against 1.5 presents a second,
    2-3% of the sliced blocks' time); a present forced at each block's start made the sliced
    blocks of 1.2 s redraw 1.5 times a second where the view does once (mirror_field / mis:
    25 ms a redraw at 960x540, 1.2% of their time)."""
    blocks = {1: [], ROUND_SLICES: []}
    clocks = {1: None, ROUND_SLICES: None}

    def block(fewest: int, block_seconds: float, min_frames: int) -> dict:
        app.session.resolution.min_still_slices = fewest
        app.resume_still_clocks(clocks[fewest])
        frames = untouched_frames(app, block_seconds, min_frames)
        clocks[fewest] = app.still_clocks()
        blocks[fewest].append(frames)
        return frames

    for _ in range(rounds):
        whole = block(ROUND_SLICES, seconds, min_frames=1)
        block(1, sum(whole["times"]), min_frames=3)
    app.session.resolution.min_still_slices = 1
    return blocks


def answering_frames(app, seconds: float) -> tuple[list[float], bool]:
    """Still frames for `seconds`, a help-overlay toggle (Tab) every KEY_EVERY of them: the times
    of the frames that got the key, and whether each of them toggled and presented it."""
    from viewer.window import FrameInput

    answers, answered = [], True
    end = time.perf_counter() + seconds
    while time.perf_counter() < end or len(answers) < 3:
        for _ in range(KEY_EVERY - 1):
            _still_step(app, FrameInput())
        before_help, presents_before = app.session.help_visible, app.presents
        answers.append(_still_step(app, FrameInput(pressed=("Tab",)))[0])
        answered &= app.session.help_visible != before_help and app.presents == presents_before + 1
    if app.session.help_visible:
        app.step(FrameInput(pressed=("Tab",)))
    return answers, answered


def still_summary(blocks: list[dict], answers: list[float], answered: bool, rng: random.Random) -> dict:
    times = [t for block in blocks for t in block["times"]]
    total = sum(times)
    return {"frames": len(times), "frame_ms_median": 1000 * statistics.median(times),
            "frame_ms_max": 1000 * max(times), "presents_per_s": sum(b["presents"] for b in blocks) / total,
            "answer_ms_median": 1000 * statistics.median(answers),
            "latency_ms": [1000 * v for v in event_latencies(times, rng, answers)],
            "samples_per_s": sum(b["pixel_samples"] for b in blocks) / total, "input_seen_in_frame": answered}


def first_round(app, limit_s: float = FIRST_ROUND_LIMIT_S) -> Optional[dict]:
    """Sliced still frames from a settled switch to the end of the view's first round (at most
    `limit_s`): their seconds, pixel samples and samples per second; None where the frame that
    settled the switch had already ended the round (a cheap view: nothing left to measure)."""
    app.session.resolution.min_still_slices = 1
    frames = still_frames_while(app, lambda times: app.renderer.slices_done < ROUND_SLICES and sum(times) < limit_s)
    seconds = sum(frames["times"])
    if seconds <= 0.0:
        return None
    return {"seconds": seconds, "pixel_samples": frames["pixel_samples"],
            "samples_per_s": frames["pixel_samples"] / seconds}


def block_rate(block: dict) -> float:
    """Pixel samples per second of a block of still frames."""
    return block["pixel_samples"] / sum(block["times"])


def paired_rate_ratios(blocks: dict[int, list[dict]]) -> list[float]:
    """Sliced / whole-sample samples per second of each pair of blocks (paired_rate_blocks): the
    still rate is their median, which a pair disturbed by other work on the machine moves less
    than a ratio of the totals."""
    return [block_rate(sliced) / block_rate(whole) for sliced, whole in zip(blocks[1], blocks[ROUND_SLICES])]


def measure_still_both(app, seconds: float, answer_seconds: float, rng: random.Random) -> tuple[dict, dict]:
    """(sliced, whole): still frames as the viewer renders them, and with every still frame made
    of whole samples per pixel (min_still_slices = a round: the viewer before pixel slices), in
    the same loop, so the two differ only in how much a frame renders. The untouched frames of
    the two alternate in RATE_ROUNDS pairs of blocks of equal time over `seconds` at least
    (paired_rate_blocks), then each answers keys for `answer_seconds`."""
    resolution = app.session.resolution
    settle_still(app)
    first = first_round(app)
    try:
        blocks = paired_rate_blocks(app, seconds / RATE_ROUNDS)
        summaries = {}
        for fewest in blocks:
            resolution.min_still_slices = fewest
            summaries[fewest] = still_summary(blocks[fewest], *answering_frames(app, answer_seconds), rng)
    finally:
        resolution.min_still_slices = 1
    sliced, whole = summaries[1], summaries[ROUND_SLICES]
    sliced["pair_ratios"] = paired_rate_ratios(blocks)
    sliced["rate_ratio"] = statistics.median(sliced["pair_ratios"])
    sliced["first_round"] = None if first is None else {**first,
                                                        "rate_ratio": first["samples_per_s"] / whole["samples_per_s"]}
    return sliced, whole


def measure_moving(app, seconds: float, rng: random.Random) -> dict:
    from viewer.window import FrameInput

    forwards = FrameInput(held=frozenset({"w"}))
    times, pixels, moved_each_frame = [], [], True
    end = time.perf_counter() + seconds
    while time.perf_counter() < end or len(times) < 3:
        position = app.session.controller.state.position
        times.append(_step_timed(app, forwards))
        pixels.append(app.renderer.film.width * app.renderer.film.height)
        moved_each_frame &= app.session.controller.state.position != position and app.last_plan.interactive
    settled = times[len(times) // 3:]  # the resolution control's first frames are its transient
    full = app.size[0] * app.size[1]
    return {"frames": len(times), "frame_ms_median": 1000 * statistics.median(settled),
            # the film the moving frames reached within their budget, a share of the window's pixels
            "pixel_share_median": statistics.median(pixels[len(pixels) // 3:]) / full,
            "frame_ms_max": 1000 * max(settled), "latency_ms": [1000 * v for v in event_latencies(settled, rng)],
            "input_seen_in_frame": moved_each_frame}


def bench_combination(app, scene_path: Path, integrator: str, config: dict, seed: int) -> dict:
    rng = random.Random(seed)
    switch = measure_switch(app, scene_path, integrator)
    still, whole = measure_still_both(app, config["still_seconds"], config["answer_seconds"], rng)
    moving = measure_moving(app, config["moving_seconds"], rng)
    for _ in range(3):  # let it settle, so the next combination starts from a still view
        app.step()
    latencies = still["latency_ms"] + moving["latency_ms"]
    return {"scene": scene_path.stem, "integrator": integrator, "switch": switch, "still": still,
            "still_whole_samples": whole, "moving": moving,
            "latency_p50_ms": percentile(latencies, 0.5), "latency_p95_ms": percentile(latencies, 0.95),
            "whole_samples_p95_ms": percentile(whole["latency_ms"] + moving["latency_ms"], 0.95),
            "still_p95_ms": percentile(still["latency_ms"], 0.95),
            "moving_p95_ms": percentile(moving["latency_ms"], 0.95)}


def print_report(results: list[dict]) -> None:
    rows = []
    for r in results:
        if "skipped" in r:
            rows.append([r["scene"], r["integrator"], "skipped: " + r["skipped"], *[""] * 12])
            continue
        switch = r["switch"]
        compile_s = "-" if switch.get("compile_s") is None else f"{switch['compile_s']:.2f}"
        rows.append([r["scene"], r["integrator"], f"{r['latency_p50_ms']:.0f}", f"{r['latency_p95_ms']:.0f}",
                     f"{r['whole_samples_p95_ms']:.0f}",
                     f"{r['still']['samples_per_s'] / 1e6:.2f}", f"{r['still']['rate_ratio']:.3f}",
                     first_round_text(r['still']), f"{r['still']['frame_ms_median']:.0f}",
                     f"{r['moving']['frame_ms_median']:.0f}", moving_pixels_text(r["moving"]),
                     f"{switch.get('load_s', math.nan):.2f}", compile_s, f"{switch['first_image_s']:.2f}"])
    print_table(["scene", "integrator", "p50 ms", "p95 ms", "p95 ms whole-sample frames", "still Msamples/s",
                 "vs whole-sample frames", "first round vs whole", "still frame ms", "moving frame ms",
                 "moving film (share of the window's pixels)",
                 "switch: load s", "compile s", "first image s"], rows,
                title=f"Input latency (event -> presented frame), target p95 <= {TARGET_LATENCY_MS:.0f} ms")


def moving_pixels_text(moving: dict) -> str:
    share = moving.get("pixel_share_median")  # (reports from before it was measured have none)
    return "-" if share is None else f"{100 * share:.1f} %"


def first_round_text(still: dict) -> str:
    """The first round's samples/s against whole-sample frames ('-' where it was not measured: a
    view that ended it in the switch's frame, or a report from before it was measured)."""
    first = still.get("first_round")
    return "-" if first is None else f"{first['rate_ratio']:.3f}"


def write_plot(results: list[dict], out_dir: Path, suffix: str = "") -> Path | None:
    measured = [r for r in results if "skipped" not in r]
    if not measured:
        return None
    plt = pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 0.32 * len(measured) + 1.8))
    labels = [f"{r['scene']} / {r['integrator']}" for r in measured]
    y = list(range(len(measured)))
    left.barh([v - 0.2 for v in y], [r["still_p95_ms"] for r in measured], 0.4, label="still")
    left.barh([v + 0.2 for v in y], [r["moving_p95_ms"] for r in measured], 0.4, label="moving")
    left.axvline(TARGET_LATENCY_MS, color="k", linestyle="--", label="target")
    left.set_yticks(y, labels)
    left.set_xlabel("p95 input latency (ms)")
    left.legend(loc="lower right")
    right.barh(y, [r["still"]["rate_ratio"] for r in measured], 0.6)
    right.axvline(TARGET_STILL_RATE, color="k", linestyle="--")
    right.set_yticks(y, [])
    right.set_xlabel("still samples/s: sliced frames / whole-sample frames")
    return save_figure(fig, Path(out_dir) / f"bench_interactive{suffix}.png")


def run(quick: bool = False, out_dir: Path = Path("reports"), scenes=None, integrators=None, size=None,
        packets: int = 0, flight: float | None = None) -> int:
    """flight: seconds of each view's moving phase (W held), instead of MOVING_SECONDS (QUICK's)."""
    from renderer.scene.catalog import resolve_scene, scene_files
    from viewer.window import ViewerApp

    config = dict(QUICK) if quick else {"scenes": tuple(p.stem for p in scene_files()), "integrators": FULL_INTEGRATORS,
                                        "size": DEFAULT_SIZE, "still_seconds": STILL_SECONDS,
                                        "answer_seconds": ANSWER_SECONDS, "moving_seconds": MOVING_SECONDS}
    if scenes is not None:
        config["scenes"] = tuple(scenes)
    if integrators is not None:
        config["integrators"] = tuple(integrators)
    if size is not None:
        config["size"] = tuple(size)
    if flight is not None:
        config["moving_seconds"] = float(flight)
    if packets:
        config["packets"] = packets
    suffix = f"_packets{packets}" if packets else ""
    t_start = time.perf_counter()
    arch = viewer_runtime()
    load_before = load_average()
    paths = [resolve_scene(name) for name in config["scenes"]]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        app = ViewerApp(paths[0], size=config["size"], show_window=False, screenshot_folder=tempfile.gettempdir(),
                        packets=packets)
    results = []
    for i, path in enumerate(paths):
        for j, integrator in enumerate(config["integrators"]):
            log(f"interactive: {path.stem} / {integrator}")
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    results.append(bench_combination(app, path, integrator, config, seed=1000 * i + j))
            except Exception as error:  # noqa: BLE001 - one combination must not end the benchmark
                results.append({"scene": path.stem, "integrator": integrator, "skipped": describe_error(error)})
    print_report(results)
    measured = [r for r in results if "skipped" not in r]
    latency_ok = bool(measured) and all(r["latency_p95_ms"] <= TARGET_LATENCY_MS for r in measured)
    rate_ok = bool(measured) and all(r["still"]["rate_ratio"] >= TARGET_STILL_RATE for r in measured
                                     if r["integrator"] != "sppm")  # sppm's passes are whole iterations
    print(f"p95 latency <= {TARGET_LATENCY_MS:.0f} ms everywhere: {verdict(latency_ok)}; still samples/s >= "
          f"{TARGET_STILL_RATE:.0%} of whole passes: {verdict(rate_ok)}")
    plot = write_plot(results, out_dir, suffix)
    variant = {"variant": f"packets{packets}"} if packets else {}  # its report kept beside the plain run's
    report = {**report_header("interactive", quick, load_before, arch=arch, config=config, **variant),
              "latency_target_ms": TARGET_LATENCY_MS, "still_rate_target": TARGET_STILL_RATE,
              "latency_ok": latency_ok, "rate_ok": rate_ok, "results": results,
              "plots": [plot.name] if plot else [], "total_seconds": time.perf_counter() - t_start}
    path = write_json(Path(out_dir) / f"bench_interactive{suffix}.json", report)
    print(f"wrote {path}  (total {report['total_seconds']:.0f} s)")
    return 0 if measured else 1

"""`python app.py compare SCENE [--time S] [--packets N]`: Lantern and Mitsuba 3 on the same scene, side by side.

A Mitsuba 3 scene file (.xml) is given to Mitsuba as it is (its -D parameters too) and to Lantern
through its reader; any other scene Mitsuba can express is converted by
renderer/bench/mitsuba_scene_dict.py. Both render at the same size and depth, interleaved in one
process, as their users run them: Lantern's progressive passes for --time seconds; Mitsuba's render
call with the samples per pixel its measured speed fits in the same time (its JIT warm, its start-up
and Lantern's compile reported apart). A long Mitsuba render is the reference (mean of passes, so
its own noise is known). The command prints each renderer's equal-time error against it (relMSE
and RMSE, the reference's noise floor subtracted), the time each needs to reach the other's error
(error ~ 1 / time for unbiased estimators), the image means, and whether Lantern's image agrees
with Mitsuba's in expectation (renderer/bench/agreement.py: per-pixel z-tests at 1% with Sidak's
correction, and the image mean); it writes a PNG of the two images and the |z| map, and a JSON.

Both draw their samples alike: a converted scene gives Mitsuba the independent sampler, and
Lantern renders it with its own independent sampler too (not the file's: a stratified sampler's
lower error would be credited to the renderer); a Mitsuba file's sampler is read by both.
--packets N traces Lantern's rays N at a time on the CPU (renderer/packets/), where the scene allows;
the line printed says whether the packets were taken.
"""
from __future__ import annotations

import json
import math
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROUNDS = 2  # Lantern and Mitsuba alternate this many times; the last round's images are judged
REFERENCE_FACTOR = 4  # the reference renders this many times the equal-time budget (at least)
REFERENCE_PASSES = 8  # at least this many passes, for the reference's variance
Z_SCALE = 5.0  # |z| shown white in the map


@dataclass
class Side:
    image: np.ndarray
    variance: np.ndarray | None  # of each pixel's mean, where the renderer keeps it
    spp: int
    seconds: float


def run_compare(args) -> int:
    from renderer.bench.mitsuba_side import MitsubaUnavailable, _import_mitsuba, set_threads
    from renderer.runtime.arch import init_taichi
    from renderer.scene.catalog import load_any, resolve_scene
    from renderer.scene.load_options import options_from_arguments

    path = resolve_scene(args.scene)
    options = options_from_arguments(args)
    scene = load_any(path, options)
    try:
        mi, variant, note = _import_mitsuba()
    except MitsubaUnavailable as error:
        raise ValueError(f"compare needs Mitsuba 3: {error}") from None
    size = tuple(args.size) if args.size else scene.render.image_size
    is_xml = Path(path).suffix.lower() == ".xml"
    if is_xml and args.size and size != scene.render.image_size:
        raise ValueError("--size: a Mitsuba scene file renders at its own film size (give it with -D where the "
                         "file has a $parameter for it)")
    if scene.render.crop is not None and size != scene.render.image_size:
        raise ValueError("--size: the scene renders its crop window, {}x{}".format(*scene.render.image_size))
    out_dir = Path(args.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    init_taichi("cpu")
    set_threads(args.threads)
    with tempfile.TemporaryDirectory(prefix="lantern-compare-") as mesh_dir:
        t0 = time.perf_counter()
        if is_xml:
            mitsuba_scene = mi.load_file(str(path), **dict(options.defines))
            notes = []
        else:
            from renderer.bench.mitsuba_scene_dict import scene_dict

            description, notes = scene_dict(scene, Path(mesh_dir), size)
            mitsuba_scene = mi.load_dict(description)
        mitsuba_load = time.perf_counter() - t0
        sampler = scene.render.sampler if is_xml else "independent"
        result = _measure(mi, mitsuba_scene, scene, size, args.seconds, args.packets, sampler)
    result.update(scene=str(path), size=list(size), mitsuba_variant=variant, mitsuba_note=note, notes=notes,
                  mitsuba_load_seconds=mitsuba_load, seconds=args.seconds)
    _print(result)
    stem = Path(path).stem
    png = _write_png(result.pop("_images"), out_dir / f"compare_{stem}.png")
    result["png"] = str(png)
    (out_dir / f"compare_{stem}.json").write_text(json.dumps(result, indent=1, default=float))
    print(f"wrote {png} and {out_dir / f'compare_{stem}.json'}")
    return 0


def _measure(mi, mitsuba_scene, scene, size, seconds: float, packets: int, sampler: str) -> dict:
    from renderer.camera import CameraFrame
    from renderer.renderer import MeshOptions, Renderer

    renderer = Renderer(scene, size, MeshOptions(packets=packets))
    camera = CameraFrame.from_spec(scene.camera)
    integrator, depth = scene.render.integrator, scene.render.max_depth
    packet_status = renderer.packet_status(integrator, renderer.features(camera), sampler)

    import taichi as ti

    def lantern() -> Side:
        renderer.reset()
        spp, t0 = 0, time.perf_counter()
        launch = 1
        while True:
            renderer.render(camera, launch, integrator, max_depth=depth, seed=1 + spp, sampler=sampler)
            ti.sync()
            spp += launch
            elapsed = time.perf_counter() - t0
            if elapsed >= seconds:
                break
            rate = spp / elapsed
            launch = max(1, min(spp, int(rate * (seconds - elapsed))))  # doubling, the last launch to the budget
        return Side(renderer.image(), renderer.film.variance_of_mean_image(), spp, elapsed)

    def mitsuba(spp: int, seed: int) -> Side:
        t0 = time.perf_counter()
        image = np.array(mi.render(mitsuba_scene, spp=int(spp), seed=int(seed)), dtype=np.float32)[..., :3]
        return Side(image, None, spp, time.perf_counter() - t0)

    t0 = time.perf_counter()
    renderer.render(camera, 1, integrator, max_depth=depth, seed=0, sampler=sampler)  # compiles (or loads) the kernels
    lantern_start = time.perf_counter() - t0
    warm = mitsuba(1, 0)  # JIT-compiles Mitsuba's kernels
    mitsuba_start = warm.seconds
    probe = mitsuba(4, 0)
    rate = 4 / max(probe.seconds, 1e-6)  # Mitsuba's samples per pixel per second, warm
    # A call of a few spp runs slower per sample than a long one: measured again at half the budget,
    # so that the timed calls fill the budget instead of stopping short of it.
    calibration = mitsuba(max(1, round(rate * seconds / 2)), 0)
    rate = calibration.spp / max(calibration.seconds, 1e-6)
    rounds = []
    for k in range(ROUNDS):
        ours = lantern()
        theirs = mitsuba(max(1, round(rate * seconds)), seed=1000 + k)
        rate = theirs.spp / max(theirs.seconds, 1e-6)
        rounds.append((ours, theirs))
    reference = _reference(mitsuba, rate, seconds)
    ours, theirs = rounds[-1]
    result = _judge(ours, theirs, reference, lantern_start, mitsuba_start, rounds)
    result["lantern"].update(sampler=sampler, packets=packets, packet_status=packet_status)
    return result


def _reference(mitsuba, rate: float, seconds: float) -> Side:
    """Mitsuba's long render: REFERENCE_PASSES passes (or more) filling REFERENCE_FACTOR budgets;
    its variance of the mean from the spread of the passes."""
    per_pass = max(1, round(rate * seconds * REFERENCE_FACTOR / REFERENCE_PASSES))
    passes = [mitsuba(per_pass, seed=10_000 + k) for k in range(REFERENCE_PASSES)]
    stack = np.stack([p.image.astype(np.float64) for p in passes])
    return Side(stack.mean(axis=0), stack.var(axis=0, ddof=1) / len(passes), per_pass * len(passes),
                sum(p.seconds for p in passes))


def _errors(image, reference: Side) -> dict:
    from renderer.bench.common import REL_MSE_EPS

    ref = reference.image
    diff = np.asarray(image, np.float64) - ref
    denominator = ref * ref + REL_MSE_EPS
    floor_mse = float(reference.variance.mean())
    floor_rel = float((reference.variance / denominator).mean())
    mse, rel = float((diff * diff).mean()), float((diff * diff / denominator).mean())
    return {"rmse": math.sqrt(mse), "rel_mse": rel, "mse_above_floor": max(mse - floor_mse, 0.0),
            "rel_mse_above_floor": max(rel - floor_rel, 0.0), "floor_rel_mse": floor_rel}


def _judge(ours: Side, theirs: Side, reference: Side, lantern_start, mitsuba_start, rounds) -> dict:
    from renderer.bench.agreement import image_mean_z, pixel_z_scores, pixel_z_test

    lantern_errors, mitsuba_errors = _errors(ours.image, reference), _errors(theirs.image, reference)

    def time_to_reach(side: Side, own: dict, target: dict) -> float | None:
        if own["rel_mse_above_floor"] <= 0 or target["rel_mse_above_floor"] <= 0:
            return None
        return side.seconds * own["rel_mse_above_floor"] / target["rel_mse_above_floor"]

    passed, fraction, _, _, level = pixel_z_test(ours.image, ours.variance, reference.image, reference.variance)
    z = pixel_z_scores(ours.image, ours.variance, reference.image, reference.variance)
    mean_z = image_mean_z((ours.image, ours.variance), (reference.image, reference.variance))
    return {
        "lantern": {"spp": ours.spp, "render_seconds": ours.seconds, "start_seconds": lantern_start,
                    "samples_per_second": ours.spp * ours.image.shape[0] * ours.image.shape[1] / ours.seconds,
                    "mean": ours.image.mean(axis=(0, 1)).tolist(), **lantern_errors,
                    "seconds_to_mitsubas_error": time_to_reach(ours, lantern_errors, mitsuba_errors)},
        "mitsuba": {"spp": theirs.spp, "render_seconds": theirs.seconds, "start_seconds": mitsuba_start,
                    "samples_per_second": theirs.spp * theirs.image.shape[0] * theirs.image.shape[1] / theirs.seconds,
                    "mean": theirs.image.mean(axis=(0, 1)).tolist(), **mitsuba_errors,
                    "seconds_to_lanterns_error": time_to_reach(theirs, mitsuba_errors, lantern_errors)},
        "reference": {"spp": reference.spp, "seconds": reference.seconds, "mean": reference.image.mean(axis=(0, 1)).tolist()},
        "rounds": [{"lantern_samples_per_second": o.spp * o.image[..., 0].size / o.seconds,
                    "mitsuba_samples_per_second": t.spp * t.image[..., 0].size / t.seconds} for o, t in rounds],
        "agreement": {"passed": bool(passed and abs(mean_z) < 2.5758), "pixel_fraction_passing": fraction,
                      "sidak_level": level, "image_mean_z": mean_z, "rule": "per-pixel z at 1% (Sidak), >= 99.75% "
                      "of pixel channels, and |image-mean z| < 2.576 (green)"},
        "_images": (ours.image, theirs.image, z),
    }


def _print(result: dict) -> None:
    from renderer.bench.common import print_table

    rows = []
    for name, key in (("Lantern", "lantern"), ("Mitsuba", "mitsuba")):
        r = result[key]
        reach = r.get("seconds_to_mitsubas_error", r.get("seconds_to_lanterns_error"))
        rows.append([name, r["spp"], f"{r['render_seconds']:.2f}", f"{r['start_seconds']:.2f}",
                     f"{r['samples_per_second'] / 1e6:.2f}", f"{r['rel_mse_above_floor']:.3g}", f"{r['rmse']:.3g}",
                     "-" if reach is None else f"{reach:.2f}", " ".join(f"{m:.4f}" for m in r["mean"])])
    print_table(["renderer", "spp", "render s", "start-up s", "Msamples/s", "relMSE-floor", "RMSE",
                 "s to the other's error", "image mean (R, G, B)"], rows,
                title=f"{result['scene']} at {result['size'][0]}x{result['size'][1]}, {result['seconds']:g} s each "
                      f"(Mitsuba {result['mitsuba_variant']}; reference {result['reference']['spp']} spp)")
    print(f"Lantern's sampler: {result['lantern']['sampler']}"
          + (f"; {result['lantern']['packet_status']}" if result["lantern"]["packet_status"] else ""))
    a = result["agreement"]
    verdict = "agree" if a["passed"] else "DIFFER"
    print(f"Lantern vs Mitsuba's reference: {verdict} ({a['pixel_fraction_passing']:.2%} of pixel channels pass the "
          f"per-pixel z-test at the Sidak level {a['sidak_level']:.1e}; image-mean z = {a['image_mean_z']:.2f})")
    for line in result["notes"]:
        print(f"note: {line}")


def _write_png(images, path: Path) -> Path:
    from renderer.output.image_io import write_png
    from renderer.output.tonemap import tonemap_array

    ours, theirs, z = images
    heat = np.clip(np.nan_to_num(np.max(z, axis=-1), posinf=Z_SCALE) / Z_SCALE, 0.0, 1.0)
    z_map = (np.stack([heat, heat * 0.3, heat * 0.3], axis=-1) * 255).astype(np.uint8)
    strip = np.concatenate([tonemap_array(ours, 0.0, "aces"), tonemap_array(theirs, 0.0, "aces"), z_map], axis=1)
    write_png(path, strip)
    return path

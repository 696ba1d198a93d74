"""GPU check: every catalog scene rendered on CUDA and on the CPU, timed, and the two images held
to each other by the test suite's z-test (tests/stats/image_tests.py).

    bash scripts/gpu_check.sh [--scenes a,b] [--size 318x179] [--seconds 2.0] [--min-spp 8]

Each scene renders at --size with its default integrator, with seed 1 on the CPU and seed 2 on
CUDA (independent noise, so the z-test of the difference is meaningful). Two phases, each
(scene, back-end) in a process of its own with an offline cache directory of its own:

  compile   the jobs side by side, half as many at a time as there are cores: Renderer built and
            one pixel slice rendered on an empty cache, i.e. every kernel the render needs
            compiled cold
  render    one job after another, on the cache the compile phase filled: the warm start, then
            whole samples per pixel, --min-spp at once and more in growing passes until
            --seconds of rendering (so each scene's spp follows its speed on each back-end:
            --min-spp at the least, about --seconds' worth; at 318x179, 14 scenes x 2 back-ends
            x 2 s plus the starts keep the whole catalog within about five minutes)

First, every pixel must have taken every sample on both sides (a back-end that drops samples can
keep the pixels' means plausible; lavapipe did, in launches of several samples a pixel). Then the
verdict per scene is the suite's (tests/stats/image_tests.py): each pixel channel's z-test of
the difference of the two means against their combined standard error at the Sidak level that
tests the whole image, with at least 99.75 % of pixel channels passing, and the image means
(green) by a two-sided z-test; the scene's level is the Sidak share of alpha = 0.01 for the whole
check (7.2e-4 for 14 scenes), so a correct back-end fails some scene with probability 0.01. The
speed-up is CUDA's samples per second over the CPU's. Prints a table, writes
reports/gpu_check.json; exit status 0 when every scene agrees, 1 if not. Without a CUDA device it
prints "skipped: no CUDA device" and exits 0. `--arch vulkan` checks the Vulkan back-end instead
(a software driver too: lavapipe, slowly; its per-pixel test needs --min-spp 256 there, since
fewer samples estimate a heavy-tailed pixel's variance too poorly). `--arch cpu` runs the same
check with the CPU on both sides (two seeds): whether the test passes a correct back-end, seen
without a GPU.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

MARKER = "LANTERN-GPU-CHECK "
SIDES = ("reference", "checked")  # the CPU, the back-end under test
SEEDS = {"reference": 1, "checked": 2}
# Not a multiple of 128 pixels: the last group of GPU threads is a partial one (56,922 = 444 x 128
# + 90), where lavapipe dropped samples (renderer.VULKAN_SAMPLES_PER_LAUNCH); 320x180 fills every
# group.
DEFAULT_SIZE = "318x179"
DEFAULT_SECONDS = 2.0
DEFAULT_MIN_SPP = 8
JOB_TIMEOUT = 900.0


# --- the comparison (importable, no Taichi) ---------------------------------------------------

@dataclass
class Agreement:
    """The z-test verdict between two (mean, variance of the mean) images."""

    passed: bool
    pixel_fraction: float  # pixel channels passing their Sidak-corrected test
    pixel_level: float  # the per-pixel significance level (Sidak, for alpha over the image)
    mean_z: float  # z of the difference of the image means (green)
    critical_z: float  # two-sided critical value at alpha

    def text(self) -> str:
        verdict = "PASS" if self.passed else "FAIL"
        return f"{verdict} ({100 * self.pixel_fraction:.2f}% px, mean z {self.mean_z:+.2f})"


def compare(reference, checked, alpha: float | None = None) -> Agreement:
    """Hold two renders of a scene to each other with the suite's statistics: `reference` and
    `checked` are (mean, variance of the mean) pairs of (H, W, 3) arrays from independent seeds;
    `alpha`: the level for this image (default the suite's ALPHA)."""
    from scipy import stats

    from renderer.bench.agreement import ALPHA, image_mean_z, pixel_z_test

    alpha = ALPHA if alpha is None else alpha
    pixels_pass, fraction, _, _, level = pixel_z_test(*reference, *checked, alpha=alpha)
    z = float(image_mean_z(reference, checked))
    critical = float(stats.norm.isf(alpha / 2))
    return Agreement(bool(pixels_pass) and abs(z) < critical, float(fraction), float(level), z, critical)


def scene_alpha(scenes: int) -> float:
    """Each scene's level, so that the whole check is at the suite's ALPHA (Sidak)."""
    from tests.stats.image_tests import ALPHA

    return -math.expm1(math.log1p(-ALPHA) / scenes)


def significance_text(scenes: int) -> str:
    from tests.stats.image_tests import ALPHA, PASS_FRACTION

    return (f"z-tests at alpha = {ALPHA:g} for the whole check ({scene_alpha(scenes):.2g} per scene): each pixel "
            f"channel at the Sidak level for the image, at least {100 * PASS_FRACTION:.2f}% passing, and the "
            "image means (green), two-sided")


# --- one render (in a process whose Taichi runtime is initialised) ----------------------------

@dataclass
class SideResult:
    mean: np.ndarray
    variance: np.ndarray  # of each pixel's mean
    spp: int
    seconds: float  # rendering alone, after the kernels were ready
    pixel_samples: tuple[int, int]  # the fewest and most samples any pixel took (accepted + dropped)


def render_side(renderer, camera, seed: int, min_spp: int, seconds: float) -> SideResult:
    """Whole samples per pixel on `renderer` (a Renderer, film reset, kernels compiled): min_spp
    at once, then passes sized from the measured rate (at most doubling the samples so far)
    until `seconds` of rendering have passed."""
    import taichi as ti

    start = time.perf_counter()
    renderer.render(camera, min_spp, seed=seed)
    ti.sync()
    done = renderer.samples_done
    while (elapsed := time.perf_counter() - start) < seconds:
        per_spp = elapsed / done
        renderer.render(camera, max(1, min(done, int((seconds - elapsed) / per_spp))), seed=seed)
        ti.sync()
        done = renderer.samples_done
    seconds = time.perf_counter() - start
    taken = renderer.film.sample_counts().astype(np.int64) + renderer.film.rejected_counts()
    return SideResult(renderer.film.mean_image(), renderer.film.variance_of_mean_image(), done, seconds,
                      (int(taken.min()), int(taken.max())))


# --- child processes --------------------------------------------------------------------------

def probe_arch(arch: str = "cuda") -> str:
    """The back-end Taichi actually starts when asked for `arch` (it falls back to the CPU, with
    a warning, where the device is missing), asked in a child process so that its banner and
    warnings stay there."""
    from renderer.bench.common import child_report, run_module

    proc = run_module("scripts.gpu_check", ["--child-probe", arch], timeout=120.0)
    report, problem = child_report(proc.stdout, proc.stderr, proc.returncode, MARKER)
    if report is None:
        raise RuntimeError(f"probing {arch}: {problem}")
    return report["arch"]


def _child_probe(arch: str) -> int:
    import taichi as ti

    ti.init(arch=getattr(ti, arch), offline_cache=False, log_level=ti.ERROR)
    print(MARKER + json.dumps({"arch": str(ti.lang.impl.current_cfg().arch).split(".")[-1]}), flush=True)
    return 0


def _child_job(argv: list[str]) -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--scene", required=True)
    parser.add_argument("--arch", required=True)
    parser.add_argument("--cache-dir", required=True)
    parser.add_argument("--size", required=True)
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--min-spp", type=int, required=True)
    parser.add_argument("--seconds", type=float, default=None, help="render for this long (else: compile only)")
    parser.add_argument("--out", type=Path, default=None, help=".npz for the mean and variance")
    args = parser.parse_args(argv)
    import taichi as ti

    from renderer.runtime.arch import init_taichi
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any, resolve_scene

    width, height = (int(v) for v in args.size.split("x"))
    used = init_taichi(args.arch, cache_dir=args.cache_dir)
    scene = load_any(resolve_scene(args.scene))
    camera = CameraFrame.from_spec(scene.camera)
    start = time.perf_counter()
    renderer = Renderer(scene, (width, height))
    renderer.render_slices(camera, 1, seed=args.seed)  # a 256th of a sample: the kernels' start
    ti.sync()
    report = {"arch": used, "integrator": scene.render.integrator, "start_s": time.perf_counter() - start}
    if args.seconds is not None:
        renderer.reset()
        side = render_side(renderer, camera, args.seed, args.min_spp, args.seconds)
        np.savez(args.out, mean=side.mean, variance=side.variance)
        report.update(spp=side.spp, render_s=side.seconds, pixel_samples=list(side.pixel_samples))
    print(MARKER + json.dumps(report), flush=True)
    return 0


def run_job(scene: str, side: str, arch: str, cache_dir: Path, args, render_to: Path | None = None) -> dict:
    """One (scene, side) job on `arch` in a child process: its report, or {"error": why}. Without
    `render_to`, the kernels compiled only."""
    import subprocess

    from renderer.bench.common import child_report, run_module

    seed = SEEDS[side]
    options = ["--child-job", "--scene", scene, "--arch", arch, "--cache-dir", str(cache_dir), "--size", args.size,
               "--seed", str(seed), "--min-spp", str(args.min_spp)]
    if render_to is not None:
        options += ["--seconds", str(args.seconds), "--out", str(render_to)]
    try:
        proc = run_module("scripts.gpu_check", options, timeout=JOB_TIMEOUT)
    except subprocess.TimeoutExpired:
        return {"error": f"no result within {JOB_TIMEOUT:.0f} s"}
    report, problem = child_report(proc.stdout, proc.stderr, proc.returncode, MARKER)
    return report if report is not None else {"error": problem}


# --- the check --------------------------------------------------------------------------------


def check(args) -> int:
    from renderer.bench.common import format_table, load_average, log, report_header, write_json
    from renderer.scene.catalog import scene_names

    began = time.perf_counter()
    load_before = load_average()
    scenes = args.scenes.split(",") if args.scenes else scene_names()
    arches = {"reference": "cpu", "checked": args.arch}
    with tempfile.TemporaryDirectory(prefix="lantern-gpu-check-") as work:
        work = Path(work)
        jobs = [(scene, side) for scene in scenes for side in SIDES]
        caches = {job: work / f"{job[0]}-{job[1]}-cache" for job in jobs}
        images = {job: work / f"{job[0]}-{job[1]}.npz" for job in jobs}
        workers = max(1, min(len(jobs), (os.cpu_count() or 2) // 2))
        log(f"compiling {len(jobs)} jobs, {workers} at a time (cold offline caches)")

        def compile_job(job):
            report = run_job(*job, arches[job[1]], caches[job], args)
            log(f"compiled {job[0]} on {arches[job[1]]}: " + report.get("error", f"{report.get('start_s', 0):.1f} s"))
            return report

        with ThreadPoolExecutor(workers) as pool:
            compiled = dict(zip(jobs, pool.map(compile_job, jobs)))
        rendered = {}
        for job in jobs:
            if "error" in compiled[job]:
                rendered[job] = compiled[job]
                continue
            log(f"rendering {job[0]} on {arches[job[1]]}")
            rendered[job] = run_job(*job, arches[job[1]], caches[job], args, images[job])
        results = [_scene_result(scene, compiled, rendered, images, scene_alpha(len(scenes))) for scene in scenes]
    rows = [[r["scene"], *_side_cells(r, "reference"), *_side_cells(r, "checked"),
             f"{r['speed_up']:.1f}x" if r.get("speed_up") else "-", r["verdict"]] for r in results]
    checked = args.arch if args.arch != "cpu" else "cpu seed 2"
    print(format_table(["scene", "cpu start s", "cpu spp", "cpu ms/spp", f"{checked} start s", f"{checked} spp",
                        f"{checked} ms/spp", "speed-up", "verdict"], rows,
                       title=f"{checked} against the CPU at {args.size} (start: Renderer built and every kernel "
                             "compiled on an empty cache; ms/spp: rendering alone, per sample per pixel); "
                             f"{significance_text(len(scenes))}"))
    failed = [r["scene"] for r in results if not r["verdict"].startswith("PASS")]
    total = time.perf_counter() - began
    print(f"\n{len(results) - len(failed)} of {len(results)} scenes agree" +
          (f"; not: {', '.join(failed)}" if failed else "") + f" ({total:.0f} s in all)")
    header = report_header("gpu_check", False, load_before, arch=args.arch, size=args.size, seconds=args.seconds,
                           min_spp=args.min_spp, seeds=SEEDS, significance=significance_text(len(scenes)))
    out = write_json(args.out, header | {"total_s": total, "scenes": results})
    print(out)
    return 1 if failed else 0


def _scene_result(scene: str, compiled: dict, rendered: dict, images: dict, alpha: float) -> dict:
    result = {"scene": scene}
    for side in SIDES:
        done = dict(rendered[(scene, side)])
        result[side] = {"cold_start_s": compiled[(scene, side)].get("start_s"),
                        "warm_start_s": done.pop("start_s", None), **done}
    errors = [f"{side}: {result[side]['error']}" for side in SIDES if "error" in result[side]]
    if errors:
        result["verdict"] = "ERROR " + "; ".join(errors)
        return result
    lost = _lost_samples(result)
    if lost:  # a back-end that drops samples fails whatever its image's statistics say
        result["verdict"] = "FAIL (samples lost: " + "; ".join(lost) + ")"
        return result
    pairs = {}
    for side in SIDES:
        with np.load(images[(scene, side)]) as data:
            pairs[side] = (data["mean"], data["variance"])
    agreement = compare(pairs["reference"], pairs["checked"], alpha)
    result.update(agreement=asdict(agreement), verdict=agreement.text(),
                  speed_up=result["reference"]["render_s"] / result["reference"]["spp"]
                  / (result["checked"]["render_s"] / result["checked"]["spp"]))
    return result


def _lost_samples(result: dict) -> list[str]:
    """What each side's pixels took where some took fewer or more than the side's spp."""
    lost = []
    for side in SIDES:
        low, high = result[side]["pixel_samples"]
        if not low == high == result[side]["spp"]:
            lost.append(f"{side}: pixels took {low}-{high} of {result[side]['spp']} samples")
    return lost


def _side_cells(result: dict, side: str) -> list:
    info = result[side]
    if "error" in info:
        return [info.get("cold_start_s") or "-", "-", "-"]
    return [info["cold_start_s"], info["spp"], 1e3 * info["render_s"] / info["spp"]]


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--child-probe"]:
        return _child_probe(argv[1])
    if argv[:1] == ["--child-job"]:
        return _child_job(argv[1:])
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arch", choices=("cuda", "vulkan", "cpu"), default="cuda",
                        help="the back-end checked against the CPU (vulkan: any Vulkan device, a software one "
                             "too; cpu: the test's false-alarm rate)")
    parser.add_argument("--scenes", help="comma-separated catalog scenes (default: all)")
    parser.add_argument("--size", default=DEFAULT_SIZE)
    parser.add_argument("--seconds", type=float, default=DEFAULT_SECONDS, help="rendering time of each side")
    parser.add_argument("--min-spp", type=int, default=DEFAULT_MIN_SPP)
    parser.add_argument("--out", type=Path, default=ROOT / "reports" / "gpu_check.json")
    args = parser.parse_args(argv)
    if args.arch != "cpu" and probe_arch(args.arch) != args.arch:
        print(f"skipped: no {'CUDA' if args.arch == 'cuda' else 'Vulkan'} device")
        return 0
    return check(args)


if __name__ == "__main__":
    sys.exit(main())

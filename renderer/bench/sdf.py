"""`python app.py bench sdf`: what sphere-tracing accuracy costs in time, per SDF scene.

For every SDF scene shipped in assets/scenes, in one process (so ratios are meaningful):

1. References, with plain settings (omega 1.0, hit threshold 0.25 pixel footprints, 1024 steps):
   - path: many spp with the 'path' integrator on its own seed (independent of the test images, so
     its noise does not correlate with theirs); the MSE its own noise adds is reported as a floor;
   - geometry: the 'normals' debug view at the test spp on the *test* seed. Debug views are
     deterministic given the seed (same pixel jitter), so a test normals image differs from this
     reference by geometric error only, without Monte Carlo noise.
2. Over-relaxation: omega 1.0 (plain sphere tracing) against 1.2 ... 1.8 at the scene's own hit
   threshold and step limit: samples/s (median of timed runs after a warm-up, run round-robin),
   mean march steps per ray, and the error at equal spp. Equal error is tested twice, each as a
   paired per-pixel difference against omega 1.0 divided by its standard error (z):
   - geometry: squared error of the normals view (no noise: any change is the marcher's);
   - path: relMSE of the path-traced images, which share one seed (common random numbers), with
     the 0.1 % pixels of largest error left out (fireflies otherwise decide the test alone).
   Equal error means worse in neither: worse is z > 3 *and* a difference over 2 % of omega 1.0's
   error (a deterministic image can show a "significant" change of a handful of silhouette
   pixels). Issue target: >= 25 % fewer steps than omega 1.0 at equal error, judged at the
   scene's own omega.
3. Sweeps of the hit threshold and of the step limit (the other knobs at the scene's values):
   geometric error (normals) against its render time, and path-traced error against time. For
   the path, samples/s is measured like in 2 (robust to a busy machine) and the image is rendered
   progressively to rate x budget spp, so every setting gets the same time budget: error at equal
   time. Seconds on the path curves are spp / measured rate.

Writes <out_dir>/bench_sdf.json and PNG plots next to it, and prints tables.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from renderer.bench.convergence import FIREFLY_TRIM  # pixels with the largest error left out of the path-traced test
from renderer.bench.common import (
    REL_MSE_EPS,
    error_difference,
    image_errors,
    load_average,
    log,
    print_table,
    pyplot,
    rel_mse,
    report_header,
    rmse,
    save_figure,
    speed_runtime,
    time_interleaved,
    verdict,
    write_json,
)

STEP_REDUCTION_TARGET = 0.25  # the target: at least 25 % fewer march steps
# "At equal error" is a one-sided equivalence test against omega 1.0: the error counts as worse only
# if the paired difference is both significant (z > 3) and larger than 2 % of the plain error;
# a deterministic image can show a "significant" difference of a few silhouette pixels.
EQUAL_ERROR_Z = 3.0
EQUAL_ERROR_MARGIN = 0.02
GEOMETRY_INTEGRATOR = "normals"


@dataclass(frozen=True)
class SdfBenchConfig:
    size: tuple[int, int] = (240, 135)
    ref_spp: int = 256  # path reference
    ref_chunk: int = 32  # spp per kernel launch while rendering the reference
    compare_spp: int = 8  # path spp per omega, equal-spp comparison
    geometry_spp: int = 8  # normals spp (test images and geometric reference)
    runs: int = 5  # timed runs (median), round-robin over the settings, after one warm-up
    sweep_runs: int = 3  # the same for the samples/s of each sweep setting
    sweep_rate_spp: int = 2  # path spp per timed run when measuring a sweep setting's samples/s
    sweep_seconds: float = 1.5  # path time budget per sweep setting
    max_sweep_spp: int = 4096
    omegas: tuple[float, ...] = (1.0, 1.2, 1.4, 1.6, 1.8, 1.9, 2.5, 3.0)
    thresholds: tuple[float, ...] = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
    step_limits: tuple[int, ...] = (32, 64, 128, 256, 512)
    ref_threshold: float = 0.25
    ref_max_steps: int = 1024
    seed: int = 1  # test images (common random numbers across settings)
    ref_seed: int = 104729  # path reference: independent of the test seed


FULL = SdfBenchConfig()
QUICK = SdfBenchConfig(size=(96, 54), ref_spp=128, compare_spp=8, geometry_spp=4, runs=3, sweep_seconds=0.4,
                       thresholds=(0.25, 1.0, 4.0), step_limits=(32, 128, 512))


def sdf_scenes(paths=None):
    from renderer.scene import load_scene
    from renderer.scene.catalog import scene_files

    scenes = [load_scene(p) for p in (paths if paths is not None else scene_files())]
    return [s for s in scenes if s.geometry == "sdf"]


class SceneBench:
    """One scene's Renderer at the benchmark size; march settings change without recompiling."""

    def __init__(self, scene, config: SdfBenchConfig):
        import taichi as ti

        from renderer.camera import CameraFrame
        from renderer.renderer import Renderer

        self._sync = ti.sync
        self.scene = scene
        self.config = config
        self.default_march = scene.render.march
        self.reference_march = replace(self.default_march, over_relaxation=1.0, hit_threshold=config.ref_threshold,
                                       max_steps=config.ref_max_steps)
        t0 = time.perf_counter()
        self.renderer = Renderer(scene, config.size)
        self.build_s = time.perf_counter() - t0
        self.camera = CameraFrame.from_spec(scene.camera)
        self.compile_s: dict[str, float] = {}

    def march(self, **changes):
        return replace(self.default_march, **changes)

    def compile(self, integrator: str) -> float:
        """First launch of `integrator` (compiles, or loads from the offline cache): 1 spp."""
        if integrator not in self.compile_s:
            self.renderer.geometry.set_march(self.default_march)
            self.renderer.reset()
            t0 = time.perf_counter()
            self.renderer.render(self.camera, 1, integrator, seed=self.config.seed)
            self._sync()
            self.compile_s[integrator] = time.perf_counter() - t0
        return self.compile_s[integrator]

    def render(self, integrator: str, march, spp: int, seed: int, chunk: int | None = None) -> None:
        """Reset the film and render `spp` samples (in launches of at most `chunk` spp)."""
        self.renderer.geometry.set_march(march)
        self.renderer.reset()
        done = 0
        while done < spp:
            n = spp - done if chunk is None else min(chunk, spp - done)
            self.renderer.render(self.camera, n, integrator, seed=seed)
            done += n
        self._sync()

    def image(self) -> np.ndarray:
        return self.renderer.image()

    def steps_per_ray(self) -> float:
        return float(self.renderer.work_stats()["work_per_ray"])

    def noise_floor(self) -> dict:
        """Expected MSE / relMSE that the reference's own noise adds to any comparison with it."""
        mean = self.renderer.image().astype(np.float64)
        var = self.renderer.film.variance_of_mean_image().astype(np.float64)
        var = np.where(np.isfinite(var), var, 0.0)
        return {"mse": float(var.mean()), "rel_mse": float((var / (mean * mean + REL_MSE_EPS)).mean())}

    def timed_settings(self, integrator: str, settings: dict, spp: int, runs: int | None = None) -> dict:
        """Time `spp` spp of `integrator` for each named march setting, round-robin, median of runs.

        Returns {name: {"timing", "image", "steps_per_ray"}}. Images are deterministic given the
        seed, so the last run's image stands for all of them.
        """
        self.compile(integrator)
        seed = self.config.seed
        calls = {name: (lambda m=m: self.render(integrator, m, spp, seed)) for name, m in settings.items()}
        out = {name: {} for name in settings}

        def keep(name):  # untimed: read back what the run just rendered
            out[name].update(image=self.image(), steps_per_ray=self.steps_per_ray())

        timings = time_interleaved(calls, runs=runs or self.config.runs, warmup=1, after=keep)
        for name in settings:
            out[name]["timing"] = timings[name]
        return out

    def converge(self, integrator: str, march, spp: int, reference: np.ndarray) -> dict:
        """Render progressively to `spp`, recording the error after 1, 2, 4, ... spp and at the end."""
        self.compile(integrator)
        self.renderer.geometry.set_march(march)
        self.renderer.reset()
        curve = []
        render_s = 0.0
        while self.renderer.samples_done < spp:
            done = self.renderer.samples_done
            n = min(max(done, 1), spp - done)
            t0 = time.perf_counter()
            self.renderer.render(self.camera, n, integrator, seed=self.config.seed)
            self._sync()
            render_s += time.perf_counter() - t0
            curve.append({"spp": self.renderer.samples_done, "render_s": render_s,
                          **image_errors(self.image(), reference, FIREFLY_TRIM)})
        return {"curve": curve, "steps_per_ray": self.steps_per_ray(), **curve[-1]}


def _worse(diff) -> bool:
    return diff.z > EQUAL_ERROR_Z and diff.relative > EQUAL_ERROR_MARGIN


def bench_scene(scene, config: SdfBenchConfig) -> dict:
    """All measurements for one scene (see the module docstring)."""
    t_scene = time.perf_counter()
    bench = SceneBench(scene, config)
    log(f"[{scene.name}] compiling path and {GEOMETRY_INTEGRATOR} programs ...")
    for integrator in ("path", GEOMETRY_INTEGRATOR):
        bench.compile(integrator)
    pixels = config.size[0] * config.size[1]

    # --- references ------------------------------------------------------------------------
    log(f"[{scene.name}] reference: {config.ref_spp} spp path, plain sphere tracing ...")
    t0 = time.perf_counter()
    bench.render("path", bench.reference_march, config.ref_spp, config.ref_seed, chunk=config.ref_chunk)
    ref_seconds = time.perf_counter() - t0
    ref_path = bench.image()
    ref_steps = bench.steps_per_ray()
    noise_floor = bench.noise_floor()
    bench.render(GEOMETRY_INTEGRATOR, bench.reference_march, config.geometry_spp, config.seed)
    ref_geometry = bench.image()
    ref_geometry_steps = bench.steps_per_ray()

    # --- over-relaxation at equal spp --------------------------------------------------------
    log(f"[{scene.name}] over-relaxation: omega {', '.join(map(str, config.omegas))} ...")
    settings = {omega: bench.march(over_relaxation=omega) for omega in config.omegas}
    path_runs = bench.timed_settings("path", settings, config.compare_spp)
    geo_runs = bench.timed_settings(GEOMETRY_INTEGRATOR, settings, config.geometry_spp)
    plain = 1.0 if 1.0 in settings else config.omegas[0]
    base, geo_base = path_runs[plain], geo_runs[plain]
    omega_rows = []
    for omega in config.omegas:
        p, g = path_runs[omega], geo_runs[omega]
        seconds = p["timing"].median
        path_diff = error_difference(p["image"], base["image"], ref_path, "rel_mse", trim=FIREFLY_TRIM)
        geo_diff = error_difference(g["image"], geo_base["image"], ref_geometry, "mse")
        omega_rows.append({
            "omega": omega,
            "path_seconds": seconds,
            "path_timing": p["timing"].as_dict(),
            "samples_per_s": config.compare_spp * pixels / seconds,
            "speedup": base["timing"].median / seconds,
            "speedup_min": base["timing"].min / p["timing"].min,
            "steps_per_ray": p["steps_per_ray"],
            "step_reduction": 1.0 - p["steps_per_ray"] / base["steps_per_ray"],
            "primary_steps_per_ray": g["steps_per_ray"],
            "primary_step_reduction": 1.0 - g["steps_per_ray"] / geo_base["steps_per_ray"],
            **image_errors(p["image"], ref_path, FIREFLY_TRIM),
            "path_vs_plain": path_diff.as_dict(),
            "geometry_rmse": rmse(g["image"], ref_geometry),
            "geometry_vs_plain": geo_diff.as_dict(),
            "geometry_seconds": g["timing"].median,
            "equal_error": not (_worse(path_diff) or _worse(geo_diff)),
        })
    default_omega = bench.default_march.over_relaxation
    judged = min(omega_rows, key=lambda r: abs(r["omega"] - default_omega))
    target = {
        "omega": judged["omega"],
        "step_reduction": judged["step_reduction"],
        "equal_error": judged["equal_error"],
        "path_z": judged["path_vs_plain"]["z"],
        "geometry_z": judged["geometry_vs_plain"]["z"],
        "passed": judged["step_reduction"] >= STEP_REDUCTION_TARGET and judged["equal_error"],
        "omegas_meeting_target": [r["omega"] for r in omega_rows
                                  if r["step_reduction"] >= STEP_REDUCTION_TARGET and r["equal_error"]],
    }

    # --- sweeps --------------------------------------------------------------------------------
    sweeps = {}
    for key, values in (("hit_threshold", config.thresholds), ("max_steps", config.step_limits)):
        log(f"[{scene.name}] sweep {key}: {', '.join(map(str, values))} ...")
        marches = {v: bench.march(**{key: v}) for v in values}
        geo = bench.timed_settings(GEOMETRY_INTEGRATOR, marches, config.geometry_spp, runs=config.sweep_runs)
        rates = bench.timed_settings("path", marches, config.sweep_rate_spp, runs=config.sweep_runs)
        rows = []
        for v in values:
            rate = config.sweep_rate_spp / rates[v]["timing"].median  # spp per second
            spp = int(min(config.max_sweep_spp, max(1, round(rate * config.sweep_seconds))))
            converged = bench.converge("path", marches[v], spp, ref_path)
            for point in converged["curve"]:
                point["seconds"] = point["spp"] / rate
            rows.append({
                "value": v,
                "geometry_seconds": geo[v]["timing"].median,
                "geometry_rmse": rmse(geo[v]["image"], ref_geometry),
                "geometry_rel_mse": rel_mse(geo[v]["image"], ref_geometry),
                "primary_steps_per_ray": geo[v]["steps_per_ray"],
                "path_spp_per_s": rate,
                "samples_per_s": rate * pixels,
                "path": converged,
            })
        sweeps[key] = {"default": getattr(bench.default_march, key), "equal_time_s": config.sweep_seconds,
                       "rows": rows}

    return {
        "scene": scene.name,
        "march_default": asdict(bench.default_march),
        "march_reference": asdict(bench.reference_march),
        "build_s": bench.build_s,
        "compile_s": dict(bench.compile_s),
        "reference": {"integrator": "path", "spp": config.ref_spp, "seed": config.ref_seed, "seconds": ref_seconds,
                      "steps_per_ray": ref_steps, "noise_floor": noise_floor,
                      "geometry_integrator": GEOMETRY_INTEGRATOR, "geometry_spp": config.geometry_spp,
                      "geometry_seed": config.seed, "geometry_steps_per_ray": ref_geometry_steps},
        "over_relaxation": omega_rows,
        "target": target,
        "sweeps": sweeps,
        "seconds": time.perf_counter() - t_scene,
    }


# --- report ------------------------------------------------------------------------------------

def print_report(results: list[dict], config: SdfBenchConfig) -> None:
    w, h = config.size
    for res in results:
        ref = res["reference"]
        march = res["march_default"]
        print(f"== {res['scene']}  ({w}x{h}; scene march: threshold {march['hit_threshold']}, "
              f"max_steps {march['max_steps']}, omega {march['over_relaxation']})")
        print(f"   first launch (compile or cache load): path {res['compile_s']['path']:.1f} s, "
              f"{GEOMETRY_INTEGRATOR} {res['compile_s'][GEOMETRY_INTEGRATOR]:.1f} s")
        print(f"   reference: {ref['spp']} spp path, omega 1.0, threshold {res['march_reference']['hit_threshold']}, "
              f"{res['march_reference']['max_steps']} steps: {ref['seconds']:.1f} s, {ref['steps_per_ray']:.1f} "
              f"steps/ray; its own noise adds relMSE ~{ref['noise_floor']['rel_mse']:.2e}")
        rows = []
        for r in res["over_relaxation"]:
            pd, gd = r["path_vs_plain"], r["geometry_vs_plain"]
            rows.append([f"{r['omega']:.1f}", r["steps_per_ray"], f"{0.0 - 100 * r['step_reduction'] + 0.0:+.1f}%",
                         r["primary_steps_per_ray"], r["samples_per_s"] / 1e6, f"{r['speedup']:.2f}x",
                         f"{r['speedup_min']:.2f}x",
                         r["rmse"], r["rel_mse"], r["rel_mse_trimmed"], f"{100 * pd['relative_difference']:+.2f}%",
                         f"{pd['z']:+.2f}", r["geometry_rmse"], f"{100 * gd['relative_difference']:+.2f}%", f"{gd['z']:+.2f}"])
        print_table(["omega", "steps/ray", "vs 1.0", "primary", "Msamples/s", "speed", "(min)", "RMSE", "relMSE", "relMSE*",
                     "d relMSE*", "z path", "geom RMSE", "d geom MSE", "z geom"], rows,
                    title=f"   over-relaxation at equal spp: path {config.compare_spp} spp (one seed for all; speed from "
                          f"the median of {config.runs} runs, (min) from the fastest), "
                          f"geometry = {GEOMETRY_INTEGRATOR} view {config.geometry_spp} spp vs plain reference; "
                          f"* = top {FIREFLY_TRIM:.1%} pixels left out; d = paired difference vs omega 1.0, z = d / its SE")
        t = res["target"]
        print(f"   target (>= {STEP_REDUCTION_TARGET:.0%} fewer steps at equal error, scene omega {t['omega']}): "
              f"{verdict(t['passed'])}  ({100 * t['step_reduction']:.1f}% fewer steps; z path {t['path_z']:+.2f}, "
              f"z geometry {t['geometry_z']:+.2f}: error no worse {'yes' if t['equal_error'] else 'no'}); "
              f"omegas meeting it: {', '.join(f'{o:.1f}' for o in t['omegas_meeting_target']) or 'none'}\n")
        for key, sweep in res["sweeps"].items():
            rows = []
            for r in sweep["rows"]:
                pr = r["path"]
                rows.append([("*" if r["value"] == sweep["default"] else "") + str(r["value"]),
                             r["geometry_seconds"], r["geometry_rmse"], r["primary_steps_per_ray"],
                             pr["steps_per_ray"], r["samples_per_s"] / 1e6, pr["spp"], pr["rmse"], pr["rel_mse"],
                             pr["rel_mse_trimmed"]])
            print_table([key, "geom s", "geom RMSE", "primary", "steps/ray", "Msamples/s", "spp@T", "RMSE@T",
                         "relMSE@T", "relMSE*@T"], rows,
                        title=f"   sweep {key} (* = scene value): geometry {GEOMETRY_INTEGRATOR} {config.geometry_spp} "
                              f"spp; path at equal time T = {sweep['equal_time_s']:g} s")
    print(f"Equal error = not worse than omega 1.0 in both paired tests: worse means z > {EQUAL_ERROR_Z:g} and a "
          f"difference over {EQUAL_ERROR_MARGIN:.0%} of the plain error.")
    print("Target summary (>= 25% fewer march steps with over-relaxation at equal error):")
    for res in results:
        t = res["target"]
        print(f"  {res['scene']:<14} omega {t['omega']}: {100 * t['step_reduction']:5.1f}% fewer steps, "
              f"z path {t['path_z']:+.2f}, z geometry {t['geometry_z']:+.2f}  {verdict(t['passed'])}")
    print(flush=True)


def write_plots(results: list[dict], out_dir: Path) -> list[Path]:
    plt = pyplot()
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    written = []
    for res in results:
        fig, axes = plt.subplots(2, 2, figsize=(11, 8))
        for col, (key, sweep) in enumerate(res["sweeps"].items()):
            rows = sweep["rows"]
            ax = axes[0, col]
            xs = [r["geometry_seconds"] for r in rows]
            ys = [max(r["geometry_rmse"], 1e-6) for r in rows]
            ax.loglog(xs, ys, "o-")
            for r, x, y in zip(rows, xs, ys):
                ax.annotate(str(r["value"]), (x, y), textcoords="offset points", xytext=(4, 4), fontsize=8)
            ax.set_xlabel(f"seconds ({res['reference']['geometry_spp']} spp {GEOMETRY_INTEGRATOR} view)")
            ax.set_ylabel("geometric error (RMSE of normals vs reference)")
            ax.set_title(f"{res['scene']}: {key} sweep, geometry")
            ax.grid(True, which="both", alpha=0.3)
            ax = axes[1, col]
            for r in rows:
                curve = r["path"]["curve"]
                ax.loglog([c["seconds"] for c in curve], [c["rel_mse_trimmed"] for c in curve], ".-",
                          label=f"{key} {r['value']}" + (" (scene)" if r["value"] == sweep["default"] else ""))
            ax.axhline(res["reference"]["noise_floor"]["rel_mse"], color="grey", ls=":", lw=1,
                       label="reference's own noise")
            ax.axvline(sweep["equal_time_s"], color="grey", ls="--", lw=1)
            ax.set_xlabel("seconds (path; spp / measured samples per second)")
            ax.set_ylabel(f"relMSE vs reference (top {FIREFLY_TRIM:.1%} px left out)")
            ax.set_title(f"{res['scene']}: {key} sweep, path-traced")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
        for ax in axes.ravel():  # label 1-2-5 steps: readable on short and long log ranges alike
            ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
            ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
            ax.xaxis.set_minor_formatter(NullFormatter())
        written.append(save_figure(fig, out_dir / f"bench_sdf_{res['scene']}_sweeps.png"))

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for res in results:
        rows = res["over_relaxation"]
        omegas = [r["omega"] for r in rows]
        line, = axes[0].plot(omegas, [r["steps_per_ray"] for r in rows], "o-", label=f"{res['scene']} (all rays)")
        axes[0].plot(omegas, [r["primary_steps_per_ray"] for r in rows], "s--", color=line.get_color(),
                     label=f"{res['scene']} (camera rays)")
        axes[1].plot(omegas, [r["speedup"] for r in rows], "o-", color=line.get_color(), label=res["scene"])
    axes[0].set_xlabel("over-relaxation omega")
    axes[0].set_ylabel("mean march steps per ray")
    axes[0].set_title("steps per ray vs omega")
    axes[0].set_ylim(bottom=0)
    axes[1].set_xlabel("over-relaxation omega")
    axes[1].set_ylabel("path samples/s relative to omega 1.0")
    axes[1].set_title("path tracing speed vs omega")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    written.append(save_figure(fig, out_dir / "bench_sdf_steps_vs_omega.png"))
    return written


def run(quick: bool = False, out_dir: Path = Path("reports"), scenes=None, config: SdfBenchConfig | None = None) -> int:
    """Benchmark every SDF scene (or the scene files `scenes`); print tables, write JSON and plots."""
    config = config or (QUICK if quick else FULL)
    out_dir = Path(out_dir)
    t_start = time.perf_counter()
    arch = speed_runtime()
    load_before = load_average()
    results = [bench_scene(scene, config) for scene in sdf_scenes(scenes)]
    if not results:
        print("no SDF scenes found")
        return 1
    print_report(results, config)
    plots = write_plots(results, out_dir)
    total = time.perf_counter() - t_start
    report = {
        **report_header("sdf", quick, load_before, arch=arch, config=asdict(config)),
        "targets": {"step_reduction": STEP_REDUCTION_TARGET, "worse_if_z_above": EQUAL_ERROR_Z,
                    "and_relative_difference_above": EQUAL_ERROR_MARGIN,
                    "firefly_trim": FIREFLY_TRIM},
        "notes": ("Error vs reference: RMSE and relMSE = mean((x-ref)^2/(ref^2+1e-2)); rel_mse_trimmed leaves out "
                  "the 0.1% pixels of largest error. Path-traced test images share one seed (common random "
                  "numbers). Equal error: neither the trimmed path relMSE nor the squared error of the deterministic "
                  "normals view (test seed, against a plain-sphere-tracing normals reference at the same seed) is "
                  "worse than omega 1.0's, worse meaning a paired per-pixel difference with z > 3 and over 2% of "
                  "the plain error. Sweep path errors "
                  "are at equal time: spp = measured samples/s x budget."),
        "scenes": results,
        "plots": [p.name for p in plots],
        "total_seconds": total,
    }
    path = write_json(out_dir / "bench_sdf.json", report)
    print(f"wrote {path} and {', '.join(p.name for p in plots)} in {out_dir}  (total {total:.0f} s)")
    return 0

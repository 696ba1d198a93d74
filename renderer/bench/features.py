"""`python app.py bench features`: what each optional effect costs, and that unused ones cost nothing.

DESIGN.md, "Simulate only what the scene calls for": kernels are compiled per `Features`, every
optional effect behind `ti.static`. This benchmark checks the claim and prices the effects. For
every catalog scene (`stress` is always skipped: its 1M-triangle BVH would be rebuilt for every
build below; pass `scenes=` to include it), with the `mis` integrator at a small size:

1. Own against everything: the scene's own Features against `Features.with_everything()` (every
   optional effect of its geometry kind forced on; effects with no data in the scene are compiled
   but their branches never taken). Per build: compile time, kernel size, samples/s.
2. Unused effects: own Features plus ONE effect the scene does not use (each boolean field of
   Features, material kind and layer that is off in the scene's own and on in `with_everything()`). Switching off an effect a scene uses would not give a valid
   image, so "own build at least as fast as a build with the unused effect removed by hand" is
   tested the other way round: cost of effect e = time(own + e) / time(own), at equal spp.
   The forced build's image is compared with the own image (same seed): forcing an effect the
   scene has no data for must still render, finite.
3. Effect costs on scenes that use them: the scene against a variant without the effect (media on
   `foggy`: fog type none and no material media; analytic fog on that variant; glass on `showcase`
   and `goblet`: dielectrics replaced by diffuse of the same colour; textures and normal maps on
   `textured`: Features without them, the texture data left in place; energy compensation on
   `studio`: Features without it; depth of field on `weekend`: a pinhole camera; dispersion on
   `prism`: the glass's index at the d line, no dispersion). Time per sample with/without, and what
   the effect buys in the image: the mean relative difference of the two images at equal spp on
   independent seeds (sum |a - b| / sum b) next to the same measure between two renders with the
   effect (the noise floor), and the change of the image's mean.

Measurements, each scene in its own Python process (a fresh Taichi runtime; one crash costs one
scene):
- Compile time and kernel size (phase A): every build gets its own Taichi runtime on one
  benchmark-private, initially empty offline cache directory. Each runtime first creates the same
  Renderers in the same order (so field layouts, and so cache keys, match phase B), then renders
  1 spp twice: compile = first call - second call. Taichi writes its offline cache when the
  runtime ends (ti.reset()), so the bytes the directory grew by are the build's kernel-size proxy;
  0 bytes means the build's code equals an earlier one's (the effect compiled to nothing). A primer
  runtime before the builds compiles the kernels every build shares (film, light tables).
- Speed (phase B): one runtime on that (now warm) cache holds every build; its first call is the
  cache-load time. Then `rounds` rounds, each timing one pass of k spp of every build (film reset
  untimed; the order rotates per round), k set so that a pass of the own build takes about
  `pass_seconds`. The paired ratio of a round, t(build) / t(own) from adjacent passes, cancels
  slow drifts of a shared machine; a build's ratio is the median over rounds, with a 95 %
  bootstrap interval of that median (rounds resampled, fixed seed).

Decision rule of the target ("a scene's own build is at least as fast as a build with an effect it
does not use"): the unused effect e FAILS when the whole 95 % interval of t(own + e) / t(own) lies
below 1 - TOLERANCE, i.e. the build carrying e is measurably faster than the scene's own build;
otherwise it passes (a cost of zero within noise passes). TOLERANCE = 2 %: different code around a
branch moves LLVM's block layout and register allocation, worth a percent or two either way that
has nothing to do with simulating an effect. The table also marks intervals wholly below 1.

Writes <out_dir>/bench_features.json and bench_features.png (bar charts of the ratios), prints tables.
"""
from __future__ import annotations

import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import traceback
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from renderer.bench.common import child_report, describe_error, dir_bytes, run_module

MARKER = "LANTERN-FEATURES "
INTEGRATOR = "mis"
TOLERANCE = 0.02  # see the module doc: code layout moves speed by a percent or two either way
BOOTSTRAP = 2000
SKIPPED_SCENES = ("stress",)


@dataclass(frozen=True)
class EffectCase:
    """Effect `effect` on scene `scene`: build `with_build` against build `without` (names below)."""

    effect: str
    scene: str
    with_build: str
    without: str


EFFECT_CASES = (
    EffectCase("media", "foggy", "own", "no media"),
    EffectCase("analytic fog", "foggy", "analytic fog", "no media"),
    EffectCase("glass", "showcase", "own", "no glass"),
    EffectCase("glass", "goblet", "own", "no glass"),
    EffectCase("textures", "textured", "own", "no textures"),
    EffectCase("normal maps", "textured", "own", "no normal maps"),
    EffectCase("energy compensation", "studio", "own", "no energy compensation"),
    EffectCase("depth of field", "weekend", "own", "pinhole"),
    EffectCase("dispersion", "prism", "own", "no dispersion"),
)


@dataclass(frozen=True)
class FeaturesBenchConfig:
    size: tuple[int, int] = (160, 90)
    rounds: int = 11  # timed passes per build, interleaved
    pass_seconds: float = 0.25  # target length of one timed pass of the own build
    max_pass_spp: int = 256
    image_spp: int = 64  # spp of the effect-cost images (task 3)
    seed: int = 1
    # The app's default level (view and render use "compile"). Unlike the other speed benchmarks this
    # one does not use "run": it compiles ~150 programs cold, and at "run" an everything build takes
    # 2-3 minutes (cornell_box 128 s, goblet 172 s here, against 7 s and 30 s for their own builds).
    optimize: str = "compile"
    fresh_cache: bool = True  # phase A (cold compile, kernel size); off: first calls hit the user's cache
    unused_effects: tuple[str, ...] | None = None  # Features.optional_effects names to force on one by one; None = all
    effect_cases: tuple[EffectCase, ...] = EFFECT_CASES
    child_timeout_s: float = 1800.0


FULL = FeaturesBenchConfig()
# --quick: no phase A (first calls against the user's offline cache: warm from the second run on)
# and only the unused effects the issue names; a few minutes instead of half an hour.
QUICK_UNUSED = ("dielectric", "has_media", "has_textures", "energy_compensation", "analytic_fog", "has_dispersion")
QUICK = FeaturesBenchConfig(size=(64, 36), rounds=5, pass_seconds=0.06, image_spp=16, fresh_cache=False,
                            unused_effects=QUICK_UNUSED)


# --- the statistics and the rule (pure, tested without Taichi) ----------------------------------

def paired_ratio(times: list[float], base: list[float], seed: int = 0) -> dict:
    """Median over rounds of times[i] / base[i] and a 95 % bootstrap interval of that median."""
    r = np.asarray(times, np.float64) / np.asarray(base, np.float64)
    rng = np.random.default_rng(seed)
    if r.size > 1:
        medians = np.median(r[rng.integers(0, r.size, size=(BOOTSTRAP, r.size))], axis=1)
        lo, hi = (float(v) for v in np.percentile(medians, [2.5, 97.5]))
    else:
        lo = hi = float(r[0])
    return {"median": float(np.median(r)), "lo": lo, "hi": hi, "ratios": r.tolist()}


def unused_effect_passes(ratio: dict, tolerance: float = TOLERANCE) -> bool:
    """The rule of the module doc: fails only if own + e is faster than own beyond noise and tolerance."""
    return ratio["hi"] >= 1.0 - tolerance


def optional_effects(own) -> list[str]:
    """What own.with_everything() adds and can be forced on one by one: Features.optional_effects."""
    return own.optional_effects()


def image_difference(a: np.ndarray, b: np.ndarray) -> float:
    """sum |a - b| / sum |b|: the share of the image that changed (0 = identical)."""
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    total = float(np.abs(b).sum())
    return float(np.abs(a - b).sum()) / total if total > 0 else float(np.abs(a - b).sum())


def mean_change(with_effect: np.ndarray, without: np.ndarray) -> float:
    """mean(with) / mean(without) - 1 over pixels and channels: the light the effect adds or takes away
    (little noise: it averages every sample of both images)."""
    m = float(np.mean(np.asarray(without, np.float64)))
    return float(np.mean(np.asarray(with_effect, np.float64))) / m - 1.0 if m > 0 else 0.0


def short(effect: str) -> str:
    return effect[4:] if effect.startswith("has_") else effect


# --- scene variants (task 3) ------------------------------------------------------------------

def _without_media(scene):
    from renderer.scene.description import FogSpec

    return replace(scene, fog=FogSpec(), materials=tuple(replace(m, medium="") for m in scene.materials))


def _analytic_fog(scene):
    """No media; the fog as the exponential-blend approximation of the scene's fog medium."""
    from renderer.scene.description import FogSpec

    density = 0.1
    if scene.fog.model == "medium":
        m = next(m for m in scene.media if m.name == scene.fog.medium)
        density = float(np.mean(np.add(m.sigma_a, m.sigma_s)))
    return replace(_without_media(scene), fog=FogSpec(model="analytic", density=density))


def _without_glass(scene):
    return replace(scene, materials=tuple(replace(m, kind="diffuse", medium="") if m.kind == "dielectric" else m
                                          for m in scene.materials))


def _without_dispersion(scene):
    """Dispersive glass with its index at the d line (587.56 nm), not dispersive."""
    from renderer.materials.dispersion import non_dispersive

    return replace(scene, materials=tuple(non_dispersive(m) for m in scene.materials))


# build name -> (scene variant, Features edit, pinhole camera)
SCENE_VARIANTS = {"no media": _without_media, "analytic fog": _analytic_fog, "no glass": _without_glass,
                  "no dispersion": _without_dispersion}
FEATURE_EDITS = {
    "no textures": lambda f: replace(f, has_textures=False, has_normal_maps=False),
    "no normal maps": lambda f: replace(f, has_normal_maps=False),
    "no energy compensation": lambda f: replace(f, energy_compensation=False),
}


# --- the child: one scene, in its own process ---------------------------------------------------

@dataclass
class Build:
    name: str
    role: str  # "own" | "everything" | "unused" | "case"
    variant: str = "own"  # which Renderer (scene variant) it renders
    effect: str | None = None  # the forced Features field of an "unused" build
    pinhole: bool = False


def _log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


class SceneWorld:
    """The Renderers of one scene and its variants in one Taichi runtime, created in a fixed order
    and primed (light tables, GGX albedo table, film read-back) so every runtime has the same field
    layout: Taichi's cache keys name fields by their ids."""

    def __init__(self, scene, variants: list[str], size):
        from renderer.camera import CameraFrame
        from renderer.renderer import Renderer

        self.renderers = {}
        for v in variants:
            s = scene if v == "own" else SCENE_VARIANTS[v](scene)
            r = Renderer(s, size)
            if INTEGRATOR in ("mis", "nee", "path"):
                r.lights()
            r.materials.ggx_albedo  # noqa: B018 - allocates the table's fields in every runtime alike
            r.image()
            r.film.stats()
            self.renderers[v] = r
        self.camera = CameraFrame.from_spec(scene.camera)
        self.pinhole = CameraFrame.from_spec(replace(scene.camera, aperture=0.0))

    def features(self, b: Build):
        r = self.renderers[b.variant]
        f = r.features(self.pinhole if b.pinhole else self.camera)
        if b.role == "everything":
            return f.with_everything()
        if b.role == "unused":
            return f.with_effect(b.effect)
        if b.name in FEATURE_EDITS:
            return FEATURE_EDITS[b.name](f)
        return f

    def render(self, b: Build, spp: int, seed: int, reset: bool = True) -> None:
        import taichi as ti

        r = self.renderers[b.variant]
        if reset:
            r.reset()
        r.render(self.pinhole if b.pinhole else self.camera, spp, INTEGRATOR, seed=seed, features=self.features(b))
        ti.sync()


def plan_builds(name: str, own, config: FeaturesBenchConfig) -> tuple[list[Build], list[EffectCase]]:
    builds = [Build("own", "own"), Build("everything", "everything")]
    wanted = optional_effects(own)
    if config.unused_effects is not None:
        wanted = [e for e in wanted if e in config.unused_effects]
    builds += [Build("+" + short(e), "unused", effect=e) for e in wanted]
    cases = []
    for case in config.effect_cases:
        if case.scene != name:
            continue
        cases.append(case)
        for b in (case.with_build, case.without):
            if all(x.name != b for x in builds):
                builds.append(Build(b, "case", variant=b if b in SCENE_VARIANTS else "own", pinhole=b == "pinhole"))
    return builds, cases


def _first_calls(world, b: Build, seed: int) -> tuple[float, float]:
    """(first 1 spp call, second 1 spp call) in seconds: first - second = compile or cache load."""
    t0 = time.perf_counter()
    world.render(b, 1, seed)
    t1 = time.perf_counter()
    world.render(b, 1, seed)
    return t1 - t0, time.perf_counter() - t1


def child_scene(path: str, config: FeaturesBenchConfig) -> dict:
    import taichi as ti

    from renderer.runtime.arch import init_taichi
    from renderer.scene import load_scene

    scene = load_scene(path)
    out = {"scene": scene.name, "geometry": scene.geometry}
    cache_dir = tempfile.mkdtemp(prefix="lantern-bench-features-") if config.fresh_cache else None
    try:
        # Which Renderers: the scene, and the variants its effect cases name.
        variants = ["own"]
        for case in config.effect_cases:
            if case.scene == scene.name:
                variants += [v for v in (case.with_build, case.without) if v in SCENE_VARIANTS and v not in variants]

        # --- phase A: primer, then each build cold in its own runtime ---------------------------
        init_taichi("cpu", cache_dir=cache_dir, optimize=config.optimize)
        t0 = time.perf_counter()
        world = SceneWorld(scene, variants, config.size)
        out["renderers_s"] = time.perf_counter() - t0
        own = world.renderers["own"].features(world.camera)
        builds, cases = plan_builds(scene.name, own, config)
        out["own_features"] = own.describe()
        out["own_effects"] = own.active_effects()
        out["cases"] = [asdict(c) for c in cases]
        info = {b.name: {"role": b.role, "effect": b.effect, "variant": b.variant, "pinhole": b.pinhole}
                for b in builds}
        if config.fresh_cache:
            ti.reset()  # the primer's kernels go to the cache: every build below shares them
            size = dir_bytes(cache_dir)
            out["shared_cache_bytes"] = size
            for b in builds:
                _log(f"[{scene.name}] compile {b.name} ...")
                try:
                    init_taichi("cpu", cache_dir=cache_dir, optimize=config.optimize)
                    world = SceneWorld(scene, variants, config.size)
                    first, second = _first_calls(world, b, config.seed)
                    info[b.name]["compile_s"] = first - second
                except Exception as error:  # noqa: BLE001 - one broken build must not hide the others
                    info[b.name]["error"] = describe_error(error)
                    info[b.name]["traceback"] = traceback.format_exc()[-2000:]
                ti.reset()
                grown = dir_bytes(cache_dir)
                info[b.name]["cache_bytes"] = grown - size
                size = grown

        # --- phase B: every build in one runtime, interleaved timing -----------------------------
        ok = [b for b in builds if "error" not in info[b.name]]
        if config.fresh_cache:  # (without phase A the primer's runtime serves)
            init_taichi("cpu", cache_dir=cache_dir, optimize=config.optimize)
            world = SceneWorld(scene, variants, config.size)
        for b in list(ok):
            try:
                first, second = _first_calls(world, b, config.seed)
                key = "load_s" if config.fresh_cache else "compile_s"
                info[b.name][key] = first - second
            except Exception as error:  # noqa: BLE001
                info[b.name]["error"] = describe_error(error)
                ok.remove(b)
        base = next((b for b in ok if b.role == "own"), None)
        if base is None:
            out["error"] = info["own"].get("error", "the own build failed")
            out["builds"] = info
            return out
        # k spp per pass: the own build's pass lasts about pass_seconds
        t0 = time.perf_counter()
        world.render(base, 4, config.seed)
        per_spp = (time.perf_counter() - t0) / 4
        k = int(min(config.max_pass_spp, max(1, round(config.pass_seconds / max(per_spp, 1e-6)))))
        out["pass_spp"] = k
        times = {b.name: [] for b in ok}
        images, rejected = {}, {}
        for rnd in range(config.rounds):
            shift = rnd % len(ok)
            for b in ok[shift:] + ok[:shift]:
                world.renderers[b.variant].reset()
                t0 = time.perf_counter()
                world.render(b, k, config.seed, reset=False)
                times[b.name].append(time.perf_counter() - t0)
                if rnd == config.rounds - 1:  # untimed: the pass's image (same seed, same spp for all)
                    r = world.renderers[b.variant]
                    images[b.name] = r.image()
                    rejected[b.name] = int(r.film.stats()["rejected"])
        pixels = config.size[0] * config.size[1]
        for b in ok:
            entry = info[b.name]
            entry["times_s"] = times[b.name]
            entry["samples_per_s"] = k * pixels / statistics.median(times[b.name])
            entry["vs_own"] = paired_ratio(times[b.name], times["own"], seed=config.seed)
            entry["rejected"] = rejected[b.name]
            entry["finite"] = bool(np.isfinite(images[b.name]).all())
            if b.variant == "own" and not b.pinhole:
                entry["image_vs_own"] = image_difference(images[b.name], images["own"])
                entry["identical_to_own"] = bool(np.array_equal(images[b.name], images["own"]))
        # Effect costs: with and without at image_spp on independent seeds, and the noise floor: the
        # same measure between two independent renders with the effect. (One seed for both would
        # correlate their noise by an unknown amount, and the floor would not compare.)
        case_out = []
        for case in cases:
            if case.with_build not in times or case.without not in times:
                case_out.append({**asdict(case), "error": "a build failed"})
                continue
            shots = {}
            for name, seed in ((case.with_build, config.seed), (case.with_build, config.seed + 1),
                               (case.without, config.seed + 2)):
                b = next(x for x in ok if x.name == name)
                world.render(b, config.image_spp, seed)
                shots[seed] = world.renderers[b.variant].image()
            w, wo = times[case.with_build], times[case.without]
            case_out.append({**asdict(case), "ratio": paired_ratio(w, wo, seed=config.seed),
                             "seconds_with": statistics.median(w), "seconds_without": statistics.median(wo),
                             "image_difference": image_difference(shots[config.seed], shots[config.seed + 2]),
                             "noise_floor": image_difference(shots[config.seed], shots[config.seed + 1]),
                             "mean_change": mean_change(shots[config.seed], shots[config.seed + 2]),
                             "mean_change_floor": mean_change(shots[config.seed], shots[config.seed + 1]),
                             "image_spp": config.image_spp})
        out["cases"] = case_out
        out["builds"] = info
        ti.reset()
        return out
    finally:
        if cache_dir:
            shutil.rmtree(cache_dir, ignore_errors=True)


def child_main(argv: list[str]) -> int:
    path, config_json = argv[0], argv[1]
    raw = json.loads(config_json)
    raw["size"] = tuple(raw["size"])
    raw["effect_cases"] = tuple(EffectCase(**c) for c in raw["effect_cases"])
    if raw["unused_effects"] is not None:
        raw["unused_effects"] = tuple(raw["unused_effects"])
    config = FeaturesBenchConfig(**raw)
    try:
        result = child_scene(path, config)
    except Exception as error:  # noqa: BLE001 - reported to the parent
        result = {"scene": Path(path).stem, "error": describe_error(error),
                  "traceback": traceback.format_exc()[-3000:]}
    print(MARKER + json.dumps(result), flush=True)
    return 0


# --- the parent ---------------------------------------------------------------------------------

def measure_scene(path, config: FeaturesBenchConfig) -> dict:
    t0 = time.perf_counter()
    try:
        proc = run_module("renderer.bench.features", ["--child", str(path), json.dumps(asdict(config))],
                          config.child_timeout_s)
    except subprocess.TimeoutExpired:
        return {"scene": Path(path).stem, "error": f"timed out after {config.child_timeout_s:.0f} s"}
    result, error = child_report(proc.stdout, proc.stderr, proc.returncode, MARKER)
    if result is None:
        return {"scene": Path(path).stem, "error": error}
    result["seconds"] = time.perf_counter() - t0
    return result


def _interval(r: dict) -> str:
    return f"{r['median']:.3f} [{r['lo']:.3f}, {r['hi']:.3f}]"


def _kb(value) -> str:
    return "-" if value is None else f"{value / 1024:.0f}"


def _s(value) -> str:
    return "-" if value is None else f"{value:.2f}"


def summarise(results: list[dict], config: FeaturesBenchConfig) -> dict:
    """Per unused effect its verdict; the overall target."""
    verdicts = []
    for res in results:
        for name, b in res.get("builds", {}).items():
            if b["role"] != "unused":
                continue
            if "vs_own" not in b:
                verdicts.append({"scene": res["scene"], "effect": b["effect"], "passed": False,
                                 "why": b.get("error", "not measured")})
                continue
            verdicts.append({"scene": res["scene"], "effect": b["effect"], "ratio": b["vs_own"]["median"],
                             "lo": b["vs_own"]["lo"], "hi": b["vs_own"]["hi"],
                             "passed": unused_effect_passes(b["vs_own"]),
                             "below_one": b["vs_own"]["hi"] < 1.0})
    return {"unused_effects": verdicts, "passed": bool(verdicts) and all(v["passed"] for v in verdicts),
            "tolerance": TOLERANCE}


def print_report(results: list[dict], summary: dict, config: FeaturesBenchConfig, missing: list[str]) -> None:
    from renderer.bench.common import print_table, verdict

    w, h = config.size
    comp = "cold compile" if config.fresh_cache else "first call"
    rows = []
    for res in results:
        if "error" in res:
            rows.append([res["scene"], "ERROR: " + res["error"]] + ["-"] * 8)
            continue
        own, every = res["builds"]["own"], res["builds"].get("everything", {})
        rows.append([res["scene"], res["geometry"], _s(own.get("compile_s")), _s(every.get("compile_s")),
                     _kb(own.get("cache_bytes")), _kb(every.get("cache_bytes")),
                     f"{own['samples_per_s'] / 1e6:.3f}",
                     f"{every['samples_per_s'] / 1e6:.3f}" if "samples_per_s" in every else "-",
                     _interval(every["vs_own"]) if "vs_own" in every else every.get("error", "-"),
                     res["pass_spp"]])
    print_table(["scene", "kind", f"{comp} own s", "all s", "kernel own KB", "all KB", "Msamples/s own", "all",
                 "t(all)/t(own) [95%]", "spp/pass"], rows,
                title=f"Own Features against every effect forced on ({INTEGRATOR}, {w}x{h}, {config.rounds} "
                      f"interleaved passes; kernel = offline-cache bytes the build added)")
    rows = []
    for res in results:
        for name, b in res.get("builds", {}).items():
            if b["role"] != "unused":
                continue
            if "vs_own" not in b:
                rows.append([res["scene"], short(b["effect"]), "ERROR: " + b.get("error", "?")] + ["-"] * 6)
                continue
            same = b.get("cache_bytes") == 0
            image = "identical" if b.get("identical_to_own") else f"{b.get('image_vs_own', float('nan')):.2e}"
            flag = verdict(unused_effect_passes(b["vs_own"])) + (" (<1)" if b["vs_own"]["hi"] < 1.0 else "")
            rows.append([res["scene"], short(b["effect"]), _s(b.get("compile_s")), _kb(b.get("cache_bytes")),
                         "yes" if same else "", _interval(b["vs_own"]), image, b["rejected"], flag])
    print_table(["scene", "+ unused effect", f"{comp} s", "kernel KB", "no new code", "t(own+e)/t(own) [95%]",
                 "image vs own", "non-finite", "verdict"], rows,
                title="Unused effects: own Features plus one effect the scene does not use (image: sum|a-b|/sum b at "
                      "the same seed and spp; (<1) = interval wholly below 1)")
    rows = []
    for res in results:
        for c in res.get("cases", []):
            if "error" in c:
                rows.append([c["effect"], res["scene"], c["without"], "ERROR: " + c["error"]] + ["-"] * 6)
                continue
            b = res["builds"]
            rows.append([c["effect"], res["scene"], c["without"], _interval(c["ratio"]),
                         _s(b[c["with_build"]].get("compile_s")), _s(b[c["without"]].get("compile_s")),
                         f"{c['image_difference']:.3f}", f"{c['noise_floor']:.3f}",
                         f"{100 * c['mean_change']:+.1f}%", f"{100 * abs(c['mean_change_floor']):.1f}%"])
    for name in missing:
        rows.append([name, "-", "missing"] + ["-"] * 7)
    print_table(["effect", "scene", "without it", "t(with)/t(without) [95%]", f"{comp} with s", "without s",
                 "image diff", "noise floor", "mean change", "(floor)"], rows,
                title=f"What each effect costs where it is used. Images at {config.image_spp} spp on independent "
                      f"seeds: image diff = sum|with - without| / sum without, noise floor = the same between two "
                      f"renders with the effect; mean change = mean(with) / mean(without) - 1")
    failed = [v for v in summary["unused_effects"] if not v["passed"]]
    print(f"Target (own build at least as fast as own + any unused effect: fails only if t(own+e)/t(own) is "
          f"below 1 - {TOLERANCE:.0%} with 95% confidence): {verdict(summary['passed'])}  "
          f"({len(summary['unused_effects']) - len(failed)}/{len(summary['unused_effects'])} effects pass"
          + ("; failing: " + ", ".join(f"{v['scene']}+{short(v['effect'])}" for v in failed) if failed else "") + ")")
    print(flush=True)


def write_plot(results: list[dict], out_dir: Path) -> Path:
    """2x2: every effect forced on (ratio, compile time), unused effects one by one, effects where used."""
    from renderer.bench.common import pyplot, save_figure

    plt = pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(15, 10), gridspec_kw={"width_ratios": [1, 1.6]})

    def errorbars(ratios):
        med = [r["median"] for r in ratios]
        return med, [[m - r["lo"] for m, r in zip(med, ratios)], [r["hi"] - m for m, r in zip(med, ratios)]]

    def bars(ax, labels, ratios, title, ylabel):
        xs = np.arange(len(ratios))
        med, err = errorbars(ratios)
        ax.bar(xs, [m - 1.0 for m in med], bottom=1.0, yerr=err, capsize=2)
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_xticks(xs)
        ax.set_xticklabels(labels, rotation=60, ha="right", fontsize=8)
        ax.set_title(title, fontsize=10)
        ax.set_ylabel(ylabel)
        ax.grid(True, axis="y", alpha=0.3)

    ok = [r for r in results if "builds" in r and "vs_own" in r["builds"].get("everything", {})]
    bars(axes[0, 0], [r["scene"] for r in ok], [r["builds"]["everything"]["vs_own"] for r in ok],
         "every effect forced on (median, 95% interval)", "t(everything) / t(own)")
    ax = axes[0, 1]
    xs = np.arange(len(ok))
    for dx, key, label in ((-0.2, "own", "own Features"), (0.2, "everything", "everything")):
        ax.bar(xs + dx, [r["builds"][key].get("compile_s") or 0.0 for r in ok], width=0.4, label=label)
    ax.set_xticks(xs)
    ax.set_xticklabels([r["scene"] for r in ok], rotation=60, ha="right", fontsize=8)
    ax.set_ylabel("compile s (first call - second call)")
    ax.set_title("compile time of the mis program", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)

    # unused effects: one column per effect, one point per scene (red: own build measurably slower)
    ax = axes[1, 1]
    effects = sorted({b["effect"] for r in results for b in r.get("builds", {}).values() if b["role"] == "unused"})
    for i, effect in enumerate(effects):
        points = [(r["scene"], b["vs_own"]) for r in results for b in r.get("builds", {}).values()
                  if b["role"] == "unused" and b["effect"] == effect and "vs_own" in b]
        for j, (_, ratio) in enumerate(points):
            x = i + (j - (len(points) - 1) / 2) * min(0.06, 0.8 / max(1, len(points)))
            color = "tab:blue" if unused_effect_passes(ratio) else "tab:red"
            ax.errorbar([x], [ratio["median"]], yerr=[[ratio["median"] - ratio["lo"]], [ratio["hi"] - ratio["median"]]],
                        fmt="o", ms=3, color=color, capsize=1.5, lw=0.8)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.axhline(1.0 - TOLERANCE, color="grey", lw=0.8, ls=":")
    ax.set_xticks(np.arange(len(effects)))
    ax.set_xticklabels([short(e) for e in effects], rotation=40, ha="right", fontsize=8)
    ax.set_ylabel("t(own + e) / t(own)")
    ax.set_title("one unused effect forced on: one point per scene (red fails: own build measurably slower)",
                 fontsize=10)
    ax.grid(True, axis="y", alpha=0.3)

    labels, ratios = [], []
    for r in results:
        for c in r.get("cases", []):
            if "ratio" in c:
                labels.append(f"{c['effect']} ({r['scene']})")
                ratios.append(c["ratio"])
    bars(axes[1, 0], labels, ratios, "effects where used: scene with / without it", "t(with) / t(without)")
    return save_figure(fig, out_dir / "bench_features.png")


def scene_paths(scenes=None) -> list[Path]:
    from renderer.scene.catalog import scene_files

    if scenes is not None:
        return [Path(s) for s in scenes]
    return [p for p in scene_files() if p.stem not in SKIPPED_SCENES]


def run(quick: bool = False, out_dir: Path = Path("reports"), scenes=None,
        config: FeaturesBenchConfig | None = None) -> int:
    """Benchmark every catalog scene but `stress` (or the scene files `scenes`); print, write JSON and a plot."""
    from renderer.bench.common import load_average, report_header, write_json

    config = config or (QUICK if quick else FULL)
    out_dir = Path(out_dir)
    t_start = time.perf_counter()
    load_before = load_average()
    results = []
    for path in scene_paths(scenes):
        _log(f"{time.perf_counter() - t_start:6.0f} s  {path.stem} ...")
        results.append(measure_scene(path, config))
        if "error" in results[-1]:
            _log(f"  {path.stem}: ERROR {results[-1]['error']}")
    missing = []
    if not any(c.get("effect") == "dispersion" for r in results for c in r.get("cases", [])):
        if any(c.effect == "dispersion" for c in config.effect_cases) and scenes is None:
            missing.append("dispersion (no scene measured it)")
    summary = summarise(results, config)
    print_report(results, summary, config, missing)
    plot = write_plot(results, out_dir)
    total = time.perf_counter() - t_start
    report = {
        **report_header("features", quick, load_before, integrator=INTEGRATOR, config=asdict(config)),
        "skipped_scenes": [s for s in SKIPPED_SCENES if scenes is None],
        "rule": (f"unused effect e fails iff the 95% bootstrap interval (rounds resampled) of the median paired ratio "
                 f"t(own+e)/t(own) lies wholly below 1 - {TOLERANCE}"),
        "notes": ("compile_s: cold compile (fresh offline cache per benchmark, one runtime per build; first 1 spp call "
                  "minus the second) when fresh_cache, else the first call against the user's cache. cache_bytes: "
                  "bytes the build added to the offline cache (0 = same code as an earlier build). load_s: first call "
                  "from the warm cache. Features.sdf_primitives/sdf_operators/mesh_primitives are not read by the "
                  "kernels (the geometry compiles what its data holds), so 'everything' adds no geometry code."),
        "missing": missing,
        "summary": summary,
        "scenes": results,
        "plot": plot.name,
        "total_seconds": total,
    }
    path = write_json(out_dir / "bench_features.json", report)
    print(f"wrote {path} and {plot.name} in {out_dir}  (total {total:.0f} s; load average before "
          f"{load_before}, after {load_average()})")
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        sys.exit(child_main(sys.argv[2:]))
    sys.exit(run(quick="--quick" in sys.argv))

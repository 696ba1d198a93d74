#!/usr/bin/env python3
"""Lantern: an interactive, progressive path tracer.

  python app.py                      open the viewer (or, without a display, render the default scene,
                                     denoised where Open Image Denoise is installed; --no-denoise: raw)
  python app.py view [SCENE]         the interactive viewer
  python app.py render SCENE ...     render headless to a PNG (tone-mapped) or EXR (linear)
  python app.py list                 scenes and integrators
  python app.py info SCENE           size, settings and Features of a scene; a model's materials,
                                     textures, extensions, instances and device memory
  python app.py bench NAME           benchmarks (see `python app.py bench --help`)
"""
from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parent


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"size must look like 640x360, got '{text}'") from None
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise argparse.ArgumentTypeError(f"size {w}x{h} is out of range (1..16384)")
    return w, h


# What the kernels take: sample indices and depths are i32 arguments, seeds u32.
I32_MAX = 2**31 - 1
U32_MAX = 2**32 - 1
# --exposure scales by 2^EV in float32: beyond this range the scale is 0 or infinite (a scene's
# render.exposure has the same bounds, renderer/scene/schema_types.py EXPOSURE_EV; not imported
# here, where the options are checked before anything of the renderer loads).
EXPOSURE_EV_RANGE = (-126.0, 127.0)
# --packets: 0 (one ray at a time) or renderer/packets/support.py's PACKET_WIDTHS, written out here
# because parsing arguments imports no Taichi (tests/commands/test_cli.py holds the two equal)
PACKET_CHOICES = (0, 4, 8, 16)


class OneLineErrorParser(argparse.ArgumentParser):
    """Usage mistakes as one line, `error: <problem>`, exit status 2 (argparse would add its usage text)."""

    def error(self, message):
        self.exit(2, f"error: {message}\n")


def _number(text: str, kind: type):
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not {'an integer' if kind is int else 'a number'}") from None
    if kind is float and not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text}")
    return value


def _render_setting(name: str, upper: int):
    """An integer option checked as the scene file checks render.<name> (renderer/scene/schema.py),
    and against `upper`, the most the kernels take."""
    def parse(text: str) -> int:
        from renderer.scene.schema import RENDER

        allowed = RENDER.field(name).range
        value = _number(text, int)
        if value not in allowed or value > upper:
            raise argparse.ArgumentTypeError(f"must be {allowed} (as render.{name} in a scene file) and at most "
                                             f"{upper}, got {value}")
        return value

    return parse


def _positive_seconds(text: str) -> float:
    value = _number(text, float)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds, got {text}")
    return value


def _positive_int(text: str) -> int:
    value = _number(text, int)
    if not 1 <= value <= I32_MAX:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text}")
    return value


def _positive_fraction(text: str) -> float:
    value = _number(text, float)
    if not 0 < value < 1e3:
        raise argparse.ArgumentTypeError(f"must be a positive relative error such as 0.02, got {text}")
    return value


def _exposure(text: str) -> float:
    value = _number(text, float)
    low, high = EXPOSURE_EV_RANGE
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(f"must be within [{low:g}, {high:g}] EV, got {text}")
    return value


def _add_input_options(command: argparse.ArgumentParser) -> None:
    """What a command that reads scenes and models may be allowed (renderer/scene/load_options.py)."""
    command.add_argument("--memory-limit", metavar="SIZE",
                         help="most memory input files may ask for, e.g. 8G (default: $LANTERN_MEMORY_LIMIT, "
                              "else half of the physical memory)")
    command.add_argument("--allow-outside-files", action="store_true",
                         help="let a model file read files outside its own folder")
    command.add_argument("-D", dest="define", action="append", metavar="NAME=VALUE",
                         help="a Mitsuba scene's parameter ($NAME in the .xml), over its <default>; repeatable")


def build_parser() -> argparse.ArgumentParser:
    from renderer.runtime.arch import ARCHES, OPTIMIZE_FOR
    from renderer.bench import BENCHMARKS
    from renderer.output.tonemap import TONEMAPPERS

    from renderer.commands.render import DEFAULT_CHECKPOINT_EVERY

    parser = OneLineErrorParser(prog="app.py", description="Lantern path tracer")
    parser.add_argument("--no-denoise", action="store_true",
                        help="with no command and no display: write the default scene's render raw (by default "
                             "it is denoised where Open Image Denoise is installed, the raw image kept beside it)")
    sub = parser.add_subparsers(dest="command")

    view = sub.add_parser("view", help="open the interactive viewer")
    view.add_argument("scene", nargs="?", default=None,
                      help="scene name, scene file (.toml, Mitsuba 3 .xml, pbrt-v4 .pbrt) or model file (default: showcase)")
    view.add_argument("--size", type=_size, default=(960, 540), help="window size WxH (default 960x540)")
    view.add_argument("--arch", choices=ARCHES, default="auto")
    view.add_argument("--integrator", default=None)
    view.add_argument("--frames", type=int, default=None, help="quit after this many frames")
    view.add_argument("--optimize", choices=OPTIMIZE_FOR, default="compile",
                      help="kernel optimisation: compile (fast compiling, the default) or run (every optimisation: a few %% faster, compiles several times longer)")
    view.add_argument("--packets", type=int, choices=PACKET_CHOICES, default=0,
                      help="trace this many rays at a time on the CPU where the scene allows (renderer/packets/; "
                           "default 0: one at a time); the HUD says where they are not taken, and why")
    _add_input_options(view)

    render = sub.add_parser("render", help="render headless to a file")
    render.add_argument("scene", nargs="?",
                        help="scene name, scene file (.toml, Mitsuba 3 .xml, pbrt-v4 .pbrt) or model file (.glb .gltf .obj .ply .stl); "
                             "with --resume, the checkpoint's scene by default")
    budget = render.add_mutually_exclusive_group()
    budget.add_argument("--spp", type=_render_setting("spp", I32_MAX), help="samples per pixel (default: the scene's)")
    budget.add_argument("--time", type=_positive_seconds, dest="seconds",
                        help="render for this many seconds (after compiling)")
    render.add_argument("--size", type=_size, help="image size WxH (default: the scene's)")
    render.add_argument("--integrator", help="integrator name (see `list`)")
    render.add_argument("--packets", type=int, choices=PACKET_CHOICES,
                        help="trace this many rays at a time on the CPU where the scene allows (renderer/packets/; "
                             "default 0: one at a time; on --resume, the checkpoint's)")
    render.add_argument("--out", type=Path, help="output .png (tone-mapped) or .exr (linear float32)")
    render.add_argument("--variance", type=Path, help="also write the variance of each pixel's mean to this .exr")
    render.add_argument("--max-depth", type=_render_setting("max_depth", I32_MAX),
                        help="1 = emitters seen directly, 2 = direct light..., -1 = unlimited")
    render.add_argument("--seed", type=_render_setting("seed", U32_MAX), help="random seed (same seed, same image)")
    render.add_argument("--arch", choices=ARCHES, help="back-end (default auto; on --resume, the checkpoint's)")
    render.add_argument("--exposure", type=_exposure, help="exposure in EV stops (PNG only; default: the scene's, 0 unless it sets one)")
    render.add_argument("--tonemapper", choices=TONEMAPPERS, help="PNG tone mapper (default aces)")
    render.add_argument("--optimize", choices=OPTIMIZE_FOR,
                        help="kernel optimisation: compile (fast compiling) or run (every optimisation: a few %% faster, "
                             "compiles several times longer); default: run for renders long enough to repay that "
                             "(renderer/runtime/optimize_choice.py), else compile; on --resume, the checkpoint's")
    render.add_argument("--checkpoint", type=Path,
                        help="save the film to this file (any name; an existing file is replaced only if it is "
                             "a checkpoint) every --checkpoint-every seconds and when stopped (default: OUT.ckpt "
                             "once a render is measured to need over a minute, removed when it completes)")
    render.add_argument("--checkpoint-every", type=_positive_seconds, default=DEFAULT_CHECKPOINT_EVERY,
                        metavar="SECONDS", help=f"seconds between checkpoints (default {DEFAULT_CHECKPOINT_EVERY:g})")
    render.add_argument("--resume", type=Path, metavar="CHECKPOINT",
                        help="continue a checkpointed render (its scene and options unless given)")
    render.add_argument("--denoise", action=argparse.BooleanOptionalAction,
                        help="write the image denoised by Intel Open Image Denoise (fed the albedo and normal "
                             "AOVs), the raw render beside it as OUT.raw.png (or .raw.exr); --no-denoise: the raw "
                             "render only (the default; on --resume, the checkpoint's choice unless given)")
    render.add_argument("--aovs", action="store_true",
                        help="also write albedo, normal, variance, raw colour and spp per pixel: as layers of an "
                             ".exr --out, or to OUT.aovs.exr beside a .png")
    render.add_argument("--noise-threshold", type=_positive_fraction, metavar="E",
                        help="adaptive sampling: stop pixels whose relative standard error is below E (e.g. 0.02); "
                             "--spp stays the maximum")
    render.add_argument("--min-spp", type=_render_setting("spp", I32_MAX), metavar="N",
                        help="adaptive sampling: samples every pixel takes before it may stop (default 16)")
    distributed = render.add_argument_group("distributed rendering (Ray)")
    distributed.add_argument("--workers", type=_positive_int, metavar="K",
                             help="render on K Ray workers: a local Ray instance started for the run, or the "
                                  "cluster of --ray-address (the image is bit-identical to a one-process render)")
    distributed.add_argument("--ray-address", metavar="ADDR",
                             help="join this Ray cluster (host:port, ray://host:port or auto) instead of starting one")
    distributed.add_argument("--worker-threads", type=_positive_int, metavar="N",
                             help="CPU threads of each worker (default: the CPUs of this machine over the local "
                                  "workers; 1 on a cluster)")
    distributed.add_argument("--chunk-spp", type=_positive_int, metavar="N",
                             help="samples per pixel of one chunk of work (default: chosen from the measured rate "
                                  "so that a chunk takes a few seconds)")
    animation = render.add_argument_group("animations")
    animation.add_argument("--frames", metavar="A:B",
                           help="render frames A to B (inclusive) of the scene's camera path; --out is a pattern "
                                "such as dir/frame_####.png")
    animation.add_argument("--fps", type=_positive_seconds, metavar="F", help="frames per second (default 24)")
    animation.add_argument("--video", type=Path, metavar="OUT.mp4", help="also assemble the frames into a video")
    animation.add_argument("--turntable", type=_positive_seconds, metavar="SECONDS",
                           help="a camera orbiting the scene's bounds once in SECONDS (instead of the scene's path)")
    _add_input_options(render)

    warm = sub.add_parser("warm-cache", help="compile the viewer's kernels for scenes ahead of time")
    warm.add_argument("scenes", nargs="*", help="scene names or files (default: every catalog scene)")
    warm.add_argument("--size", type=_size, default=(960, 540), help="the viewer's window size WxH (default 960x540)")
    warm.add_argument("--integrators", metavar="A,B", help="comma-separated integrators (default: all)")
    warm.add_argument("--arch", choices=ARCHES, default="auto", help="the back-end the viewer will use")
    warm.add_argument("--packets", type=int, choices=PACKET_CHOICES, default=0,
                      help="the rays a packet the viewer will take (view --packets)")

    compare = sub.add_parser("compare", help="Lantern and Mitsuba 3 on the same scene, at equal time")
    compare.add_argument("scene", help="scene name, scene file (.toml, Mitsuba 3 .xml) or model file")
    compare.add_argument("--time", type=_positive_seconds, default=10.0, dest="seconds",
                         help="seconds each renderer renders (default 10); the reference takes four times that")
    compare.add_argument("--size", type=_size, help="image size WxH (default: the scene's)")
    compare.add_argument("--threads", type=_positive_int, help="Mitsuba's threads (default: all, as Lantern's)")
    compare.add_argument("--packets", type=int, choices=PACKET_CHOICES, default=0,
                         help="trace Lantern's rays this many at a time on the CPU where the scene allows "
                              "(renderer/packets/; default 0: one at a time)")
    compare.add_argument("--out-dir", type=Path, default=ROOT / "out", help="where the PNG and JSON go (default out/)")
    _add_input_options(compare)

    sub.add_parser("list", help="list scenes and integrators")
    info = sub.add_parser("info", help="describe a scene")
    info.add_argument("scene")
    _add_input_options(info)

    bench = sub.add_parser("bench", help="run a benchmark")
    bench.add_argument("name", choices=sorted(BENCHMARKS))
    bench.add_argument("--quick", action="store_true", help="a short run (smaller sizes, fewer repeats)")
    bench.add_argument("--out-dir", type=Path, default=ROOT / "reports")
    bench.add_argument("--data", type=Path, metavar="DIR",
                       help="mitsuba-tests: a checkout of the mitsuba-data repository (its tests/scenes); "
                            "scenes: a folder of scene folders in pbrt-v4 form (e.g. gonsolo/bitterli)")
    bench.add_argument("--only", metavar="TEXT",
                       help="mitsuba-tests, scenes: only the scenes whose name contains TEXT")
    bench.add_argument("--mitsuba", action="store_true",
                       help="scenes: also render each scene that converts with Mitsuba 3 for the same time")
    bench.add_argument("--packets", type=int, choices=PACKET_CHOICES[1:],
                       help="interactive: the viewer traces this many rays at a time where a scene allows")
    bench.add_argument("--flight", type=_positive_seconds, metavar="S",
                       help="interactive: seconds of each view's flight, W held (default 2; 0.7 with --quick)")
    bench.add_argument("--time", type=float, metavar="S", dest="seconds",
                       help="scenes: seconds of sampling per scene (default 20; 2 with --quick)")
    return parser


def has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def cmd_render(args) -> int:
    from renderer.commands.interrupts import StopRequests
    from renderer.commands.render import run_render

    with StopRequests() as stop:
        return run_render(args, stop)


def cmd_compare(args) -> int:
    from renderer.commands.compare import run_compare

    return run_compare(args)


def cmd_list(_args) -> int:
    from renderer.integrators import INTEGRATORS
    from renderer.scene import load_scene
    from renderer.scene.catalog import scene_files

    print("scenes:")
    for path in scene_files():
        scene = load_scene(path)
        print(f"  {scene.name:<14} {scene.geometry:<5} {scene.description}")
    print("integrators:")
    for name, cls in INTEGRATORS.items():
        print(f"  {name:<14} {cls.description}")
    return 0


def cmd_info(args) -> int:
    from renderer.scene.catalog import load_any, resolve_scene
    from renderer.scene.load_options import options_from_arguments

    scene = load_any(resolve_scene(args.scene), options_from_arguments(args))
    r = scene.render
    print(f"scene:       {scene.name}  ({scene.path})")
    print(f"description: {scene.description}")
    if scene.geometry == "sdf":
        from renderer.scene.features import scene_features

        features = scene_features(scene)
        print(f"geometry:    sdf, {len(scene.sdf_objects)} top-level objects, "
              f"{sum(1 for o in scene.sdf_objects for _ in o.walk())} nodes")
    else:
        from renderer.mesh_world import prepare_mesh_scene as assemble

        mesh = assemble(scene)
        features = mesh.features(scene)
        counts = ", ".join(f"{n} {k}s" for k, n in mesh.data.counts.items() if n)
        print(f"geometry:    mesh, {len(scene.mesh_objects)} objects: {counts}")
    own = ", ".join(f"{m.name} ({m.kind})" for m in scene.materials)
    print(f"materials:   {own or '-'}" + ("" if scene.geometry == "sdf" else "  (plus those of the model files)"))
    env = scene.environment
    print(f"environment: {env.kind}" + (f" {env.file.name}" if env.file else "") + f", intensity {env.intensity}")
    crop = "" if r.crop is None else (f", cropped to {r.crop[2]}x{r.crop[3]} at ({r.crop[0]}, {r.crop[1]}) from the "
                                      "top left (only the window is rendered)")
    print(f"render:      {r.width}x{r.height}{crop}, {r.spp} spp, max depth {r.max_depth}, {r.integrator}")
    print("features:")
    for key, value in features.describe().items():
        print(f"  {key:<20} {value}")
    if scene.geometry == "mesh":
        from renderer.scene.model_report import scene_report

        print("\n".join(scene_report(scene, mesh)))
    return 0


def cmd_view(args) -> int:
    from renderer.runtime.arch import init_taichi
    from renderer.scene.catalog import DEFAULT_SCENE, resolve_scene
    from viewer.window import run_viewer

    from renderer.scene.limits import check_film
    from renderer.scene.load_options import options_from_arguments

    path = resolve_scene(args.scene or DEFAULT_SCENE)
    options = options_from_arguments(args)
    check_film(path, *args.size, options.budget, "--size", aovs=True)  # the viewer keeps denoising AOVs
    init_taichi(args.arch, optimize=args.optimize)
    return run_viewer(path, size=args.size, integrator=args.integrator, max_frames=args.frames, load_options=options,
                      packets=args.packets)


def cmd_warm_cache(args) -> int:
    from renderer.integrators import integrator_names, make_integrator
    from renderer.scene.catalog import resolve_scene, scene_files
    from viewer.cache_warmer import warm_scenes

    scenes = [resolve_scene(name) for name in args.scenes] if args.scenes else scene_files()
    integrators = None
    if args.integrators:
        integrators = [name.strip() for name in args.integrators.split(",") if name.strip()]
        for name in integrators:
            make_integrator(name)  # an unknown name: one line, before any process starts
    print(f"warming the viewer's kernels at {args.size[0]}x{args.size[1]}: {len(scenes)} scenes, "
          f"{', '.join(integrators or integrator_names())}", flush=True)
    results = warm_scenes(scenes, args.size, integrators, args.arch, report=lambda line: print(line, flush=True),
                          packets=args.packets)
    return 1 if any(result["error"] for result in results) else 0


DATA_BENCHMARKS = ("mitsuba-tests", "scenes")  # the benchmarks that read a data set of their own (--data, --only)


def cmd_bench(args) -> int:
    from renderer.bench import run_benchmark

    options = {"quick": args.quick, "out_dir": args.out_dir}
    if args.name in DATA_BENCHMARKS:
        options.update(data=args.data, only=args.only)
    elif args.data is not None or args.only is not None:
        raise ValueError(f"--data and --only are for bench {', '.join(DATA_BENCHMARKS)}, not {args.name}")
    if args.seconds is not None:
        if args.name != "scenes":
            raise ValueError(f"--time is for bench scenes, not {args.name}")
        if args.seconds <= 0:
            raise ValueError(f"--time {args.seconds:g}: needs a positive number of seconds")
        options["seconds"] = args.seconds
    if args.packets:
        if args.name != "interactive":
            raise ValueError(f"--packets is for bench interactive, not {args.name}")
        options["packets"] = args.packets
    if args.flight is not None:
        if args.name != "interactive":
            raise ValueError(f"--flight is for bench interactive, not {args.name}")
        options["flight"] = args.flight
    if args.mitsuba:
        if args.name != "scenes":
            raise ValueError(f"--mitsuba is for bench scenes, not {args.name}")
        options["mitsuba"] = True
    return run_benchmark(args.name, **options)


def _one_line_warning(message, category, filename, lineno, line=None):
    return f"warning: {message}\n"


def main(argv: list[str] | None = None) -> int:
    sys.path.insert(0, str(ROOT))
    warnings.formatwarning = _one_line_warning
    from renderer.scene.errors import SceneError

    from renderer.commands.interrupts import Interrupted, exit_code

    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as stopped:  # a usage error (already said in one line) or --help
        return stopped.code
    if args.command is None:
        if has_display():
            args = parser.parse_args(["view"])
        else:
            from renderer.commands.first_run import first_run_arguments

            argv, said = first_run_arguments(denoise=not args.no_denoise)
            print(said, file=sys.stderr)
            args = parser.parse_args(argv)
    elif args.no_denoise:
        print("error: --no-denoise before a command is for the default run (python app.py --no-denoise); "
              "a render takes it after its options (app.py render SCENE ... --no-denoise)", file=sys.stderr)
        return 2
    handlers = {"view": cmd_view, "render": cmd_render, "list": cmd_list, "info": cmd_info, "bench": cmd_bench,
                "warm-cache": cmd_warm_cache, "compare": cmd_compare}
    try:
        return handlers[args.command](args)
    except (SceneError, ValueError, RuntimeError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    except Interrupted as stopped:  # a stop signal before there was anything to save
        print(f"\n{stopped}", file=sys.stderr)
        return exit_code(stopped.signum)
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        return exit_code(signal.SIGINT)


if __name__ == "__main__":
    sys.exit(main())

"""The automatic --optimize level of `render` (renderer/runtime/optimize_choice.py): pure logic, no renders."""
import math
from dataclasses import replace

import pytest

import app
from renderer.commands.headless import RenderJob
from renderer.runtime.optimize_choice import (BREAK_EVEN_SECONDS, CORE_SECONDS_PER_SAMPLE, RenderLength, choose_for_render,
                                      choose_level, expected_seconds)
from renderer.scene.description import GEOMETRY_KINDS

PIXELS = 640 * 360
CPU_RENDER = RenderLength(seconds=None, spp=64, pixels=PIXELS, geometry="sdf", integrator="mis", on_cpu=True,
                          cpu_threads=2)


def break_even_spp(length: RenderLength) -> float:
    """The spp at which the estimated rendering time reaches the break-even time."""
    return (BREAK_EVEN_SECONDS[length.geometry] * length.cpu_threads
            / (CORE_SECONDS_PER_SAMPLE[length.geometry] * length.pixels))


# Kinds whose "run" kernels were measured faster (a finite break-even), and those measured no faster.
REPAYING = [kind for kind in GEOMETRY_KINDS if math.isfinite(BREAK_EVEN_SECONDS[kind])]
NEVER = [kind for kind in GEOMETRY_KINDS if not math.isfinite(BREAK_EVEN_SECONDS[kind])]


def test_every_geometry_kind_has_figures():
    assert set(BREAK_EVEN_SECONDS) == set(GEOMETRY_KINDS) == set(CORE_SECONDS_PER_SAMPLE)
    assert all(v > 0 for v in [*BREAK_EVEN_SECONDS.values(), *CORE_SECONDS_PER_SAMPLE.values()])
    assert REPAYING  # some kind of scene gains from long renders, or the rule is pointless


@pytest.mark.parametrize("given", ["compile", "run"])
def test_an_explicit_level_always_wins(given):
    lengths = (replace(CPU_RENDER, spp=1), replace(CPU_RENDER, spp=10**9), replace(CPU_RENDER, spp=None, seconds=1e6))
    for length in lengths:
        for resumed in (None, "compile", "run"):
            choice = choose_level(given, resumed, length)
            assert (choice.level, choice.automatic) == (given, False)


@pytest.mark.parametrize("resumed", ["compile", "run"])
def test_a_resumed_render_keeps_its_checkpoints_level(resumed):
    """Bit-identity with the uninterrupted render: the same kernels, whatever the length left."""
    for length in (replace(CPU_RENDER, spp=1), replace(CPU_RENDER, spp=10**9)):
        choice = choose_level(None, resumed, length)
        assert (choice.level, choice.automatic) == (resumed, False)


@pytest.mark.parametrize("geometry", REPAYING)
def test_a_time_budget_past_the_break_even_runs_faster_kernels(geometry):
    break_even = BREAK_EVEN_SECONDS[geometry]
    for on_cpu in (True, False):  # a budget is a budget on every back-end
        length = replace(CPU_RENDER, geometry=geometry, spp=None, on_cpu=on_cpu)
        assert choose_level(None, None, replace(length, seconds=break_even * 1.01)).level == "run"
        assert choose_level(None, None, replace(length, seconds=break_even)).level == "compile"
        assert choose_level(None, None, replace(length, seconds=60.0)).level == "compile"


@pytest.mark.parametrize("geometry", REPAYING)
def test_an_spp_target_is_judged_by_its_estimated_time(geometry):
    length = replace(CPU_RENDER, geometry=geometry)
    threshold = break_even_spp(length)
    above, below = math.ceil(threshold * 1.01), math.floor(threshold * 0.99)
    assert choose_level(None, None, replace(length, spp=above)).level == "run"
    assert choose_level(None, None, replace(length, spp=below)).level == "compile"
    # the scenes' own budgets (64-256 spp at 640x360) are short renders on a small machine
    assert choose_level(None, None, replace(length, spp=256)).level == "compile"


@pytest.mark.parametrize("geometry", NEVER)
def test_kinds_no_faster_with_run_kernels_keep_fast_compiles_however_long(geometry):
    for length in (replace(CPU_RENDER, geometry=geometry, spp=None, seconds=1e9),
                   replace(CPU_RENDER, geometry=geometry, spp=2**31 - 1, pixels=16384**2)):
        choice = choose_level(None, None, length)
        assert (choice.level, choice.automatic) == ("compile", True)
        assert "no faster" in choice.reason


def test_the_estimate_scales_with_samples_and_threads():
    base = expected_seconds(CPU_RENDER)
    assert expected_seconds(replace(CPU_RENDER, spp=128)) == pytest.approx(2 * base)
    assert expected_seconds(replace(CPU_RENDER, pixels=2 * PIXELS)) == pytest.approx(2 * base)
    assert expected_seconds(replace(CPU_RENDER, cpu_threads=8)) == pytest.approx(base / 4)
    # A render long on 2 threads is short on 64: the compile then weighs more.
    spp = math.ceil(break_even_spp(CPU_RENDER) * 2)
    assert choose_level(None, None, replace(CPU_RENDER, spp=spp)).level == "run"
    assert choose_level(None, None, replace(CPU_RENDER, spp=spp, cpu_threads=64)).level == "compile"


@pytest.mark.parametrize("change", [{"on_cpu": False}, {"integrator": "normals"}, {"integrator": "sppm"}])
def test_without_a_per_sample_estimate_spp_renders_keep_fast_compiles(change):
    length = replace(CPU_RENDER, spp=10**9, **change)
    assert expected_seconds(length) is None
    choice = choose_level(None, None, length)
    assert (choice.level, choice.automatic) == ("compile", True)
    assert "no estimate" in choice.reason


def test_the_printed_line_names_the_level_and_the_reason():
    seconds = 2 * BREAK_EVEN_SECONDS[CPU_RENDER.geometry]
    line = choose_level(None, None, replace(CPU_RENDER, spp=None, seconds=seconds)).line()
    assert "\n" not in line and "run" in line and f"--time {seconds:g}" in line
    spp_line = choose_level(None, None, CPU_RENDER).line()
    assert "compile" in spp_line and "64 spp" in spp_line and "2 threads" in spp_line


def test_adaptive_sampling_counts_only_the_samples_every_pixel_takes():
    huge = math.ceil(break_even_spp(replace(CPU_RENDER, cpu_threads=512)) * 2)
    job = RenderJob(spp=huge, size=(640, 360), integrator="mis")
    assert choose_for_render(None, None, job, "sdf", "cpu").level == "run"
    adaptive = replace(job, noise_threshold=0.02, min_spp=16)
    assert choose_for_render(None, None, adaptive, "sdf", "cpu").level == "compile"
    # on CUDA the per-sample cost is unknown: --spp keeps fast compiles
    assert choose_for_render(None, None, job, "sdf", "cuda").level == "compile"


def _plan(argv, capsys):
    from renderer.commands.render import plan_render

    plan = plan_render(app.build_parser().parse_args(argv))
    return plan, capsys.readouterr().err


def test_render_plans_choose_and_say_so(tmp_path, capsys):
    out = ["--out", str(tmp_path / "x.png"), "--arch", "cpu"]
    long_budget = f"{2 * BREAK_EVEN_SECONDS['sdf']:g}"
    plan, err = _plan(["render", "showcase", "--time", long_budget, *out], capsys)
    assert plan.optimize == "run" and plan.checkpoints.header.optimize == "run"
    assert [line for line in err.splitlines() if "kernels optimised for" in line] == [
        f"kernels optimised for run: --time {long_budget}; faster kernels repay their longer compile after about "
        f"{BREAK_EVEN_SECONDS['sdf']:.0f} s of rendering"]
    plan, err = _plan(["render", "showcase", "--spp", "4", *out], capsys)
    assert plan.optimize == "compile" and "kernels optimised for compile" in err
    plan, err = _plan(["render", "showcase", "--time", long_budget, "--optimize", "compile", *out], capsys)
    assert plan.optimize == "compile" and "kernels optimised" not in err


def test_a_resumed_plan_keeps_the_checkpoints_level(tmp_path, capsys):
    from renderer.output.checkpoint import save_checkpoint
    from tests.output.checkpoint_helpers import film_state, header_for
    from tests.scene_builder import furnace_toml

    scene = tmp_path / "s.toml"
    scene.write_text(furnace_toml(env=0.8, albedo=0.6, max_depth=3))
    checkpoint = tmp_path / "run.ckpt"
    save_checkpoint(checkpoint, header_for(scene, optimize="run"),  # 8 spp of 24x16: "compile" were it new
                    film_state(24, 16, 1.0))
    plan, err = _plan(["render", "--resume", str(checkpoint)], capsys)
    assert plan.optimize == "run" and "kernels optimised" not in err
    plan, _ = _plan(["render", "--resume", str(checkpoint), "--optimize", "compile"], capsys)
    assert plan.optimize == "compile"

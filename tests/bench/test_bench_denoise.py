"""`bench denoise` on a tiny configuration: its curves, targets and report hold together."""
import json
import types

import numpy as np
import pytest

from renderer.bench import denoise
from renderer.output.denoise import unavailable_reason

pytestmark = pytest.mark.skipif(unavailable_reason() is not None, reason="pyoidn is not installed here")

TINY = denoise.DenoiseBenchConfig(size=(48, 27), reference_s=3.0, reference_launch_s=0.5, max_spp=16,
                                  equal_time_spp=8, thresholds=(0.05, 0.5), min_spp=2, frame_size=(64, 36),
                                  scenes=("cornell_box",), viewer_size=(40, 24), viewer_reference_s=2.0)


def test_tiny_run_writes_curves_targets_and_a_plot(tmp_path, capsys):
    assert denoise.run(out_dir=tmp_path, config=TINY) == 0
    report = json.loads((tmp_path / "bench_denoise.json").read_text())
    (scene,) = report["scenes"]
    curve = scene["curve"]
    assert [p["spp"] for p in curve] == [1, 2, 4, 8, 16]
    assert all(a["seconds"] <= b["seconds"] for a, b in zip(curve, curve[1:]))
    # The denoiser's whole point: at 1 spp its output is far closer to the reference than the raw image.
    assert curve[0]["denoised"] < 0.5 * curve[0]["raw"]
    assert scene["raw_spp_matching_denoised_8"]["spp"] > 8
    # No pixel stops before min spp. The adaptive renders get the uniform render's time, so on a
    # loaded machine one may end early. A pixel stops only at a check, after min spp, 2 min spp,
    # 4 min spp ... whole rounds (at the second at the earliest: below the threshold at two checks
    # in a row), and at a check every pixel has that many samples: a render that stopped pixels
    # gave every pixel at least min spp, and one that ended before 2 min spp stopped none.
    for adaptive in scene["adaptive"]:
        assert 0.0 <= adaptive["stopped_fraction"] <= 1.0
        if adaptive["stopped_fraction"] > 0.0:
            assert adaptive["mean_spp"] >= TINY.min_spp, adaptive
        if adaptive["max_spp"] < 2 * TINY.min_spp:  # (max_spp: the pixel slices rendered, in rounds)
            assert adaptive["stopped_fraction"] == 0.0, adaptive
    # A loose threshold stops pixels at the second check if the budget reached it (the film there
    # is the same however the passes fell: fixed seed, whole rounds).
    loose = max(scene["adaptive"], key=lambda a: a["threshold"])
    if loose["max_spp"] >= 2 * TINY.min_spp:
        assert loose["stopped_fraction"] > 0.0, loose
    # The paired test compares the adaptive image with the uniform one at equal time: at the budget,
    # or, where the adaptive render stopped every pixel before the budget, as it was then.
    for adaptive in scene["adaptive"]:
        paired, uniform = adaptive["paired"], adaptive["uniform"]
        assert paired["a"] == pytest.approx(adaptive["rel_mse"], rel=1e-6)
        assert paired["b"] == pytest.approx(uniform["rel_mse"], rel=1e-6)
        if adaptive["ended_early"]:
            assert adaptive["stopped_fraction"] == 1.0
            assert abs(uniform["seconds"] - adaptive["seconds"]) <= denoise.PASS_S
            assert uniform["spp"] <= scene["uniform"]["spp"]
        else:
            assert uniform == scene["uniform"]
        assert paired["standard_error"] > 0.0 and paired["z"] == pytest.approx(
            paired["difference"] / paired["standard_error"])
        assert adaptive["paired_trimmed"]["trim"] == 1e-3
    assert scene["target_adaptive"]["paired"] in ("better", "worse", "tie")
    # ... and it is the verdict of the default threshold's own paired comparison (the verdicts of
    # known comparisons: test_the_paired_comparison_of_known_images_gives_the_known_verdict).
    default = next(a for a in scene["adaptive"] if a["threshold"] == denoise.DEFAULT_THRESHOLD)
    assert scene["target_adaptive"]["threshold"] == denoise.DEFAULT_THRESHOLD
    assert scene["target_adaptive"]["paired"] == denoise.paired_verdict(default["paired"])
    assert scene["target_adaptive"]["paired_trimmed"] == denoise.paired_verdict(default["paired_trimmed"])
    assert all(p["denoised_quick_corrected"] >= 0.0 for p in curve)
    assert (tmp_path / "bench_denoise_cornell_box.png").stat().st_size > 0
    assert report["denoiser_frame_s"] > 0.0 and report["denoiser_frame_quick_s"] > 0.0
    # The target again at the "viewer's" size: its own reference, both forms of the AOVs, raw at 128 spp.
    viewer = scene["viewer_size"]
    assert viewer["size"] == [40, 24] and viewer["reference"]["spp"] >= 1
    assert viewer["seconds_128"] > viewer["seconds_8"] > 0.0 and viewer["seconds_8_with_features"] > 0.0
    assert all(viewer[k] >= 0.0 for k in ("raw_8", "denoised_8_with_features", "denoised_8_without_features", "raw_128"))
    # The Cornell box has no texture: the target takes its 8 spp without feature samples.
    assert viewer["feature_boost"] == 0 and viewer["denoised_8"] == viewer["denoised_8_without_features"]
    assert viewer["passed"] == (viewer["denoised_8"] < viewer["raw_128"])
    out = capsys.readouterr().out
    assert "Adaptive against uniform sampling at equal time" in out and "Denoiser time per 64x36 frame" in out


def test_the_paired_verdict_needs_a_difference_at_the_five_percent_level():
    verdict = denoise.paired_verdict
    assert verdict({"z": -2.5}) == "better" and verdict({"z": 2.5}) == "worse"
    assert verdict({"z": -1.5}) == verdict({"z": 1.9}) == "tie" and verdict(None) == "n/a"


def test_the_paired_comparison_of_known_images_gives_the_known_verdict():
    """error_difference and paired_verdict, as bench_scene chains them, on images whose errors are
    known: relative noise of 5 % against 20 % is better (z far below -1.96), the other way round
    worse; the same errors at other pixels are a tie (difference 0 up to the summation order);
    one firefly in the better image, 1000 times the pixel's value, makes its untrimmed comparison a
    tie (a single outlier gives z = 1 whatever its size) and leaves the trimmed one better."""
    from renderer.bench.common import error_difference

    rng = np.random.default_rng(11)
    shape = (27, 48, 3)
    reference = np.full(shape, 0.5)
    low_noise = rng.standard_normal(shape)
    close = reference * (1.0 + 0.05 * low_noise)
    far = reference * (1.0 + 0.2 * rng.standard_normal(shape))

    def verdict(a, b, trim=0.0):
        paired = error_difference(a, b, reference, "rel_mse", trim=trim).as_dict()
        return denoise.paired_verdict(paired), paired["z"]

    assert verdict(close, far)[0] == "better" and verdict(close, far)[1] < -10.0
    assert verdict(far, close)[0] == "worse" and verdict(far, close)[1] > 10.0
    shuffled = reference * (1.0 + 0.05 * rng.permutation(low_noise.reshape(-1, 3)).reshape(shape))
    assert verdict(close, shuffled)[0] == verdict(shuffled, close)[0] == "tie"
    firefly = close.copy()
    firefly[13, 20] *= 1000.0
    assert verdict(firefly, far)[0] == "tie" and verdict(firefly, far)[1] == pytest.approx(1.0, abs=0.01)
    assert verdict(firefly, far, trim=1e-3)[0] == "better"


def test_the_scene_s_targets_come_from_its_default_threshold(monkeypatch):
    """bench_scene's targets from known figures (the renders and races stood in for): the adaptive
    target is the default threshold's, its paired verdicts those of its own comparisons (here
    better untrimmed, worse trimmed), the denoising target denoised at 8 spp against raw at the
    last point."""
    from renderer.bench.common import load_named_scene

    def paired(z):
        return {"metric": "rel_mse", "a": 0.0, "b": 0.0, "difference": z, "standard_error": 1.0, "trim": 0.0, "z": z}

    def adaptive(threshold, error, z, z_trimmed):
        return {"threshold": threshold, "rel_mse_corrected": error, "paired": paired(z),
                "paired_trimmed": paired(z_trimmed),
                "uniform": {"spp": 16, "seconds": 1.0, "rel_mse": 0.2, "rel_mse_corrected": 0.2}}

    curve = [{"spp": n, "seconds": 0.1 * n, "raw_corrected": 0.8 / n, "denoised_corrected": 0.1 / n}
             for n in (1, 2, 4, 8, 16)]
    races = [adaptive(0.5, 0.3, 2.5, 0.0), adaptive(denoise.DEFAULT_THRESHOLD, 0.1, -2.5, 3.0),
             adaptive(0.01, 0.25, 0.0, -3.0)]
    monkeypatch.setattr(denoise, "timed_render", lambda *args: 0.0)
    monkeypatch.setattr(denoise, "reference_render", lambda *args: (None, 0.0, {"spp": 1}))
    monkeypatch.setattr(denoise, "denoise_curve", lambda *args: curve)
    monkeypatch.setattr(denoise, "at_equal_time", lambda *args: ({"max_spp": 16, "seconds": 1.0, "rel_mse": 0.2,
                                                                  "rel_mse_corrected": 0.2}, races))
    config = denoise.DenoiseBenchConfig(size=(8, 8), max_spp=16, equal_time_spp=8, viewer_size=None)
    result = denoise.bench_scene(load_named_scene("cornell_box"), None, config)
    assert result["target_adaptive"] == {"threshold": denoise.DEFAULT_THRESHOLD, "adaptive": 0.1, "uniform": 0.2,
                                         "passed": True, "paired": "better", "paired_trimmed": "worse"}
    assert result["target_denoise"] == {"denoised_8": 0.1 / 8, "raw_128": 0.8 / 16, "raw_spp": 16, "passed": True}


def test_an_equal_time_race_on_a_clock_of_slices(monkeypatch):
    """at_equal_time on a clock that counts the pixel slices the renderer has rendered (1 ms each)
    instead of the machine's seconds: the race is then the same on every machine, and what the tiny
    run can only check where the machine's timing let it happen is checked here outright.

    Budget 16 spp, min spp 2: uniform sampling takes its 16 spp and stops nothing; threshold 0.5
    stops pixels (at checks, so each has at least min spp) and at least as many as 0.05 does; a
    threshold of 100 stops every pixel at the second check (2 min spp) and so ends early, compared
    with the uniform render as it was then. Budget 3 spp, below 2 min spp: nothing stops."""
    from renderer.bench.common import load_named_scene
    from renderer.camera import CameraFrame
    from renderer.film.pixel_slices import ROUND_SLICES
    from renderer.renderer import Renderer

    scene = load_named_scene("cornell_box")
    renderer = Renderer(scene, (16, 9), aovs=True)
    camera = CameraFrame.from_spec(scene.camera)
    renderer.render(camera, 64, denoise.INTEGRATOR, seed=99)
    reference = renderer.image()
    slice_s = 1e-3
    monkeypatch.setattr(denoise, "time", types.SimpleNamespace(perf_counter=lambda: renderer.slices_done * slice_s))
    config = denoise.DenoiseBenchConfig(thresholds=(0.5, 0.05, 100.0), min_spp=2)
    budget = 16 * ROUND_SLICES * slice_s
    uniform, (loose, default, everything) = denoise.at_equal_time(renderer, camera, reference, 0.0, budget, config)
    assert uniform["stopped_fraction"] == 0.0 and 16 <= uniform["max_spp"] < 17
    for adaptive in (loose, default):
        assert not adaptive["ended_early"] and adaptive["uniform"] == denoise.uniform_summary(uniform)
        assert adaptive["max_spp"] == uniform["max_spp"]
    assert 0.0 < loose["stopped_fraction"] < 1.0 and loose["mean_spp"] >= config.min_spp
    assert loose["stopped_fraction"] >= default["stopped_fraction"] > 0.0
    assert loose["mean_spp"] < default["mean_spp"] < uniform["mean_spp"]
    assert everything["ended_early"] and everything["stopped_fraction"] == 1.0
    assert everything["max_spp"] == everything["mean_spp"] == 2 * config.min_spp
    assert everything["seconds"] < denoise.EARLY_END * budget
    compared = everything["uniform"]
    assert abs(compared["seconds"] - everything["seconds"]) <= denoise.PASS_S
    assert compared["spp"] < uniform["max_spp"] and compared["seconds"] < uniform["seconds"]

    short = 3 * ROUND_SLICES * slice_s  # below the second check: no pixel can stop
    uniform, adaptive = denoise.at_equal_time(renderer, camera, reference, 0.0, short, config)
    assert uniform["max_spp"] < 2 * config.min_spp
    for figures in adaptive:
        assert figures["max_spp"] < 2 * config.min_spp and figures["stopped_fraction"] == 0.0, figures
        assert not figures["ended_early"]


def test_raced_renders_equal_renders_made_alone():
    """Taking turns keeps each film aside between passes: a contestant's image (and a kept turn's)
    is bit for bit the render of as many slices made in one go, and every contestant gets at
    least its budget (or stops every pixel first)."""
    from renderer.bench.common import load_named_scene
    from renderer.camera import CameraFrame
    from renderer.renderer import AdaptiveSettings, Renderer

    scene = load_named_scene("cornell_box")
    renderer = Renderer(scene, (16, 9), aovs=True)
    camera = CameraFrame.from_spec(scene.camera)
    config = denoise.DenoiseBenchConfig(thresholds=(0.2,), min_spp=2)
    renderer.render(camera, 1, denoise.INTEGRATOR)  # compiles: not in a turn's time
    contestants = [denoise.Contestant(None, 0.3, keep_turns=True), denoise.Contestant(0.2, 0.3)]
    denoise.race(renderer, camera, contestants, config)
    # A kept turn is the film as it was then: the render of its slices made in one go, below.
    kept = contestants[0].turns
    assert len(kept) >= 2 and [t[0] for t in kept] == sorted(t[0] for t in kept)
    contestants.append(contestants[0].at(kept[(len(kept) - 1) // 2][0]))
    assert contestants[-1].slices_done == kept[(len(kept) - 1) // 2][2] < contestants[0].slices_done
    for contestant in contestants[:2]:
        assert contestant.seconds >= contestant.budget_s or contestant.pixels_active == 0
    for contestant in contestants:
        renderer.restore(contestant.state, contestant.slices_done)
        raced = renderer.image()
        renderer.reset()
        renderer.set_adaptive(None if contestant.threshold is None else AdaptiveSettings(contestant.threshold, 2))
        renderer.render_slices(camera, contestant.slices_done, denoise.INTEGRATOR, seed=config.seed)
        renderer.set_adaptive(None)
        np.testing.assert_array_equal(raced, renderer.image())

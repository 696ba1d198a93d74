"""`bench denoise` on a tiny configuration: its curves, targets and report hold together."""
import json

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

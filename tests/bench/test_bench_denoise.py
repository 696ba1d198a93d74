"""`bench denoise` on a tiny configuration: its curves, targets and report hold together."""
import json

import pytest

from renderer.bench import denoise
from renderer.denoise import unavailable_reason

pytestmark = pytest.mark.skipif(unavailable_reason() is not None, reason="pyoidn is not installed here")

TINY = denoise.DenoiseBenchConfig(size=(48, 27), reference_s=3.0, reference_launch_s=0.5, max_spp=16,
                                  equal_time_spp=8, thresholds=(0.05, 0.5), min_spp=2, frame_size=(64, 36),
                                  scenes=("cornell_box",))


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
    # The paired test compares the adaptive image with the uniform one at the budget's spp.
    for adaptive in scene["adaptive"]:
        paired = adaptive["paired"]
        assert paired["a"] == pytest.approx(adaptive["rel_mse"], rel=1e-6)
        assert paired["b"] == pytest.approx(scene["uniform"]["rel_mse"], rel=1e-6)
        assert paired["standard_error"] > 0.0 and paired["z"] == pytest.approx(
            paired["difference"] / paired["standard_error"])
        assert adaptive["paired_trimmed"]["trim"] == 1e-3
    assert scene["target_adaptive"]["paired"] in ("better", "worse", "tie")
    assert all(p["denoised_quick_corrected"] >= 0.0 for p in curve)
    assert (tmp_path / "bench_denoise_cornell_box.png").stat().st_size > 0
    assert report["denoiser_frame_s"] > 0.0 and report["denoiser_frame_quick_s"] > 0.0
    out = capsys.readouterr().out
    assert "Adaptive against uniform sampling at equal time" in out and "Denoiser time per 64x36 frame" in out


def test_the_paired_verdict_needs_a_difference_at_the_five_percent_level():
    verdict = denoise.paired_verdict
    assert verdict({"z": -2.5}) == "better" and verdict({"z": 2.5}) == "worse"
    assert verdict({"z": -1.5}) == verdict({"z": 1.9}) == "tie" and verdict(None) == "n/a"

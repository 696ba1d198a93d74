"""Smoke test of `bench photons` on a tiny caustic scene: it runs, reports both integrators and
the caustic-region errors, and writes its JSON and plot (correctness of the plumbing, not speed)."""
import json
import math

import pytest

from renderer.bench.common import verdict
from renderer.bench.photons import PhotonBenchConfig, corrected, region_mask, run
from tests.scene_builder import furnace_toml, scene_from_toml


def test_region_mask_covers_the_fraction():
    mask = region_mask((10, 20), (0.25, 0.5, 0.75, 1.0))
    assert mask.sum() == 5 * 10 and mask[5:, 5:15].all()


def test_floor_correction_never_goes_negative():
    at = {"rmse": 0.1, "rel_mse": 0.01, "rmse_caustic": 0.2, "rel_mse_caustic": 0.05}
    floor = {"mse": 0.02, "rel_mse": 0.001, "mse_caustic": 0.01, "rel_mse_caustic": 0.1}
    out = corrected(at, floor)
    assert out["rmse"] == 0.0 and out["rel_mse_caustic"] == 0.0
    assert out["rmse_caustic"] == pytest.approx(math.sqrt(0.2 ** 2 - 0.01))  # sqrt(RMSE^2 - floor MSE)


def test_runs_on_a_tiny_glass_scene(tmp_path, capsys):
    scene = scene_from_toml(tmp_path, furnace_toml(ball_kind="dielectric", max_depth=6), "tiny_caustic")
    config = PhotonBenchConfig(size=(16, 9), budget_s=0.3, reference_s=0.6, reference_launch_s=0.3,
                               scenes=(str(scene.path),))
    assert run(out_dir=tmp_path, config=config) == 0
    report = json.loads((tmp_path / "bench_photons.json").read_text())
    res = report["scenes"][0]
    assert set(res["curves"]) == {"mis", "sppm"} and res["caustic_pixels"] == 16 * 9
    printed = capsys.readouterr().out
    target = res["target"]  # the floor-corrected caustic relMSE of each curve at the budget
    assert target["mis"] == res["curves"]["mis"]["at_budget_floor_corrected"]["rel_mse_caustic"]
    assert target["sppm"] == res["curves"]["sppm"]["at_budget_floor_corrected"]["rel_mse_caustic"]
    assert target["passed"] == (target["sppm"] < target["mis"])
    assert (f"Target (tiny_caustic): sppm's caustic relMSE (floor-corrected) below mis's at equal time: "
            f"{target['sppm']:.4g} vs {target['mis']:.4g}  {verdict(target['passed'])}") in printed
    assert (tmp_path / "bench_photons_tiny_caustic.png").exists()

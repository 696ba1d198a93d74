"""Smoke test of `bench photons` on a tiny caustic scene: it runs, reports both integrators and
the caustic-region errors, and writes its JSON and plot (correctness of the plumbing, not speed)."""
import json

from renderer.bench.photons import PhotonBenchConfig, corrected, region_mask, run
from tests.scene_builder import furnace_toml, scene_from_toml


def test_region_mask_covers_the_fraction():
    mask = region_mask((10, 20), (0.25, 0.5, 0.75, 1.0))
    assert mask.sum() == 5 * 10 and mask[5:, 5:15].all()


def test_floor_correction_never_goes_negative():
    at = {"rmse": 0.1, "rel_mse": 0.01, "rmse_caustic": 0.2, "rel_mse_caustic": 0.05}
    floor = {"mse": 0.02, "rel_mse": 0.001, "mse_caustic": 0.01, "rel_mse_caustic": 0.1}
    out = corrected(at, floor)
    assert out["rmse"] == 0.0 and out["rel_mse_caustic"] == 0.0 and abs(out["rmse_caustic"] - 0.1732) < 1e-3


def test_runs_on_a_tiny_glass_scene(tmp_path, capsys):
    scene = scene_from_toml(tmp_path, furnace_toml(ball_kind="dielectric", max_depth=6), "tiny_caustic")
    config = PhotonBenchConfig(size=(16, 9), budget_s=0.3, reference_s=0.6, reference_launch_s=0.3,
                               scenes=(str(scene.path),))
    assert run(out_dir=tmp_path, config=config) == 0
    report = json.loads((tmp_path / "bench_photons.json").read_text())
    res = report["scenes"][0]
    assert set(res["curves"]) == {"mis", "sppm"} and res["caustic_pixels"] == 16 * 9
    printed = capsys.readouterr().out
    assert "Target (tiny_caustic)" in printed and ("PASS" in printed or "FAIL" in printed)
    assert (tmp_path / "bench_photons_tiny_caustic.png").exists()

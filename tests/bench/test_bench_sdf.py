"""`bench sdf` end to end on a tiny scene and tiny settings (the real run takes minutes)."""
import json

from renderer.bench.common import REL_MSE_EPS, verdict

def test_sdf_benchmark_on_a_tiny_scene(tiny_scene, tmp_path, capsys):
    from renderer.bench.sdf import STEP_REDUCTION_TARGET, SdfBenchConfig, run

    config = SdfBenchConfig(size=(32, 18), ref_spp=4, ref_chunk=2, compare_spp=2, geometry_spp=2, runs=1,
                            sweep_rate_spp=1, sweep_seconds=0.02, max_sweep_spp=4, omegas=(1.0, 1.6),
                            thresholds=(0.5, 2.0), step_limits=(8, 64))
    out = tmp_path / "reports"
    assert run(quick=True, out_dir=out, scenes=[tiny_scene], config=config) == 0
    report = json.loads((out / "bench_sdf.json").read_text())
    (scene,) = report["scenes"]
    assert scene["scene"] == "tiny"
    rows = scene["over_relaxation"]
    assert [r["omega"] for r in rows] == [1.0, 1.6]
    assert rows[0]["step_reduction"] == 0.0 and rows[0]["path_vs_plain"]["difference"] == 0.0
    assert all(r["steps_per_ray"] > 0 and r["samples_per_s"] > 0 for r in rows)
    # the target is judged on the row of the scene's own omega, by its step reduction and equal error
    target = scene["target"]
    judged = min(rows, key=lambda r: abs(r["omega"] - scene["march_default"]["over_relaxation"]))
    assert target["omega"] == judged["omega"] and target["step_reduction"] == judged["step_reduction"]
    assert target["equal_error"] == judged["equal_error"]
    assert target["passed"] == (judged["step_reduction"] >= STEP_REDUCTION_TARGET and judged["equal_error"])
    for key, values in (("hit_threshold", [0.5, 2.0]), ("max_steps", [8, 64])):
        sweep = scene["sweeps"][key]
        assert [r["value"] for r in sweep["rows"]] == values
        for r in sweep["rows"]:
            assert 1 <= r["path"]["spp"] <= 4 and r["path"]["curve"]
            # normals are mapped to [0, 1], so relMSE = mean(e^2 / (ref^2 + eps)) lies between
            # RMSE^2 / (1 + eps) and RMSE^2 / eps: both figures come from the same two images
            rmse2 = r["geometry_rmse"] ** 2
            assert rmse2 / (1.0 + REL_MSE_EPS) * (1 - 1e-9) <= r["geometry_rel_mse"] <= rmse2 / REL_MSE_EPS * (1 + 1e-9)
    # a coarser threshold takes fewer steps on the camera rays
    sweep = scene["sweeps"]["hit_threshold"]["rows"]
    assert sweep[1]["primary_steps_per_ray"] < sweep[0]["primary_steps_per_ray"]
    for name in report["plots"]:
        assert (out / name).stat().st_size > 1000
    assert "bench_sdf_steps_vs_omega.png" in report["plots"]
    printed = capsys.readouterr().out
    assert (f"  {'tiny':<14} omega {target['omega']}: {100 * target['step_reduction']:5.1f}% fewer steps, "
            f"z path {target['path_z']:+.2f}, z geometry {target['geometry_z']:+.2f}  {verdict(target['passed'])}"
            in printed.splitlines())

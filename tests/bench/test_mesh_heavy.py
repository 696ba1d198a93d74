"""`bench integrators`' mesh-heavy comparison with Mitsuba (renderer/bench/mesh_heavy.py): the
reading of its curves exactly, and Mitsuba's version of the stress scene where Mitsuba is
installed (the real comparison takes minutes)."""
import math

import numpy as np
import pytest

from renderer.bench import mesh_heavy


def curve(seconds_per_spp: float, error_at_1: float, max_spp: int = 64) -> list[dict]:
    """An unbiased renderer's curve: relMSE ~ 1/spp, time ~ spp."""
    return [{"spp": n, "seconds": n * seconds_per_spp, "rel_mse_floor": error_at_1 / n}
            for n in (2 ** k for k in range(int(math.log2(max_spp)) + 1))]


def test_rows_reach_the_target_where_their_curves_do():
    pixels = 1000
    row = mesh_heavy.row_to_target(curve(0.01, 1.0), pixels, target=1.0 / 16)
    assert row["spp_to_target"] == pytest.approx(16.0) and not row["extrapolated"]
    assert row["seconds_to_target"] == pytest.approx(0.16)
    assert row["samples_per_s"] == pytest.approx(pixels / 0.01)
    far = mesh_heavy.row_to_target(curve(0.01, 1.0, max_spp=8), pixels, target=1.0 / 32)
    assert far["spp_to_target"] == pytest.approx(32.0) and far["extrapolated"]  # relMSE ~ 1/spp past the end


def test_caption_and_rows_say_what_was_measured():
    rows = {"Mitsuba path/independent": mesh_heavy.row_to_target(curve(0.01, 1.0), 100, 1 / 64),
            "Lantern mis/sobol": mesh_heavy.row_to_target(curve(0.02, 0.25), 100, 1 / 64)}
    for r in rows.values():
        r["speed"] = rows["Mitsuba path/independent"]["seconds_to_target"] / r["seconds_to_target"]
    result = {"scene": "stress", "size": [32, 18], "max_depth": 8, "target_spp": 64, "target_rel_mse": 1 / 64,
              "references": {"lantern": {"spp": 4000}, "mitsuba": {"spp": 1024}}, "references_rel_mse": 0.01,
              "rows": rows, "best_lantern": "Lantern mis/sobol", "best_mitsuba": "Mitsuba path/independent",
              "best_ratio": 2.0, "passed": True}
    table = mesh_heavy.summary_rows(result)
    assert [r[0] for r in table] == list(rows) and table[1][-1] == "2.00x"
    assert "PASS" in mesh_heavy.caption(result) and "2.00x Mitsuba's speed" in mesh_heavy.caption(result)


def test_mitsuba_renders_its_stress_scene():
    from renderer.bench import mitsuba_side as ms

    if not ms.is_available():
        pytest.skip("Mitsuba 3 is not installed (the project's `reference` extra)")
    mi, _, _ = ms._import_mitsuba()
    scene = mi.load_dict(ms.stress_scene_dict(32, 18, 8))
    image = ms.render_scene(scene, 4, seed=0)
    assert image.shape == (18, 32, 3) and np.isfinite(image).all() and ms.samples_taken(scene) == 4
    assert 0.05 < float(image.mean()) < 50.0  # lit by the sunset, not black, not blown out

"""`bench integrators`' mesh-heavy comparison with Mitsuba (renderer/bench/mesh_heavy.py): the
reading of its curves exactly, and Mitsuba's version of the stress scene (the real comparison
takes minutes). Mitsuba comes with the project's `test` extra (`pip install -e ".[test]"`, as
scripts/setup.sh installs it); without it the Mitsuba tests are skipped, saying so."""
import ast
import math
import os
import subprocess
import sys
from pathlib import Path

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


ROOT = Path(__file__).resolve().parents[2]
NO_MITSUBA = ("Mitsuba 3 is not installed: `pip install -e \".[test]\"` (or `.[reference]`) installs it; "
              "scripts/setup.sh does")


def test_mitsuba_renders_its_stress_scene():
    from renderer.bench import mitsuba_side as ms

    if not ms.is_available():
        pytest.skip(f"{NO_MITSUBA} ({ms.availability()['note']})")
    mi, _, _ = ms._import_mitsuba()
    scene = mi.load_dict(ms.stress_scene_dict(32, 18, 8))
    image = ms.render_scene(scene, 4, seed=0)
    assert image.shape == (18, 32, 3) and np.isfinite(image).all() and ms.samples_taken(scene) == 4
    assert 0.05 < float(image.mean()) < 50.0  # lit by the sunset, not black, not blown out


def test_without_a_libllvm_it_can_trust_mitsuba_renders_on_its_scalar_variant():
    """Where no libLLVM is named (DRJIT_LIBLLVM_PATH unset and no Debian libllvm19), Dr.Jit would
    pick whatever libLLVM the system has, and one too old for it aborts the process at the first
    render: the LLVM variants are not tried then, the scalar one renders, and the note says what
    to install. In a child process: the variant is chosen once per process."""
    from importlib.util import find_spec

    if find_spec("mitsuba") is None:
        pytest.skip(NO_MITSUBA)
    code = ("from renderer.bench import mitsuba_side as ms\n"
            "ms.DEFAULT_LIBLLVM = '/nonexistent/libLLVM-19.so'\n"
            "info = ms.availability()\n"
            "mi = ms._import_mitsuba()[0]\n"
            "image = ms.render_scene(ms.load_cornell_box(8, 6, 3), 2, seed=0)\n"
            "print(repr((info['variant'], image.shape, float(image.mean()) > 0, info['note'])))\n")
    env = {k: v for k, v in os.environ.items() if k != "DRJIT_LIBLLVM_PATH"}
    child = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True,
                           timeout=300)
    assert child.returncode == 0, child.stderr[-2000:]
    variant, shape, lit, note = ast.literal_eval(child.stdout.strip().splitlines()[-1])
    assert (variant, shape, lit) == ("scalar_rgb", (6, 8, 3), True), child.stdout
    assert "apt-get install libllvm19" in note and "using scalar_rgb" in note, note

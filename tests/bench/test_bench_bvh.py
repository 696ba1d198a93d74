"""Smoke tests of `bench bvh`: its measurement of one tiny mesh, its helpers, and a whole run on a
tiny configuration (the real run takes minutes). The measurement is checked without Embree and
with it, against Embree's hits; embreex comes with the project's `test` extra (`pip install -e
".[test]"`, as scripts/setup.sh installs it), and without it that check is skipped, saying so."""
import json

import numpy as np
import pytest

from renderer.bench import bvh, bvh_measure, embree_side
from renderer.bench.common import write_json
from renderer.bench.rays import FAR, camera_rays, random_rays

TINY = bvh_measure.MeshSpec("ico-320", "icosphere", (("subdivisions", 2), ("radius", 1.0)))


def tiny_config(**kw):
    base = dict(meshes=(TINY,), build_runs=1, build_runs_large=1, camera=(24, 16), incoherent_rays=2000,
                trace_runs=1, strategies=("sah", "midpoint"), traversals=("stack", "stackless"),
                triangle_tests=("watertight",), leaf_mesh=TINY.name, leaf_sizes=(2, 4))
    base.update(kw)
    return bvh_measure.BvhBenchConfig(**base)


def test_rays():
    lo, hi = np.array([-1.0, -0.5, -2.0]), np.array([1.0, 0.5, 2.0])
    cam = camera_rays(lo, hi, 8, 4)
    assert cam.origins.shape == (32, 3) and cam.directions.dtype == np.float32
    assert np.allclose(np.linalg.norm(cam.directions, axis=1), 1.0, atol=1e-6)
    closest, shadow = random_rays(lo, hi, 500, seed=3)
    assert np.all(closest.t_max == np.float32(FAR))
    ends = shadow.origins + shadow.directions * shadow.t_max[:, None]
    assert np.all(ends >= lo - 1e-4) and np.all(ends <= hi + 1e-4)  # segments end at the targets


def test_agreement_counts():
    lantern = np.array([1.0, -1.0, 2.0, 3.0, -1.0], np.float32)
    embree = np.array([1.00001, 1e30, 2.1, 1e30, 4.0], np.float32)
    hit = np.array([True, False, True, False, True])
    a = embree_side.agreement(lantern, embree, hit)
    assert a["rays"] == 5 and a["disagreeing"] == 3 and a["fraction"] == pytest.approx(0.4)
    assert (a["lantern_only_hits"], a["embree_only_hits"], a["distance_mismatches"]) == (1, 1, 1)


@pytest.mark.parametrize("with_embree", [False, True], ids=["lantern", "with-embree"])
def test_measure_tiny_mesh(tmp_path, with_embree):
    tris = TINY.load()
    assert tris.shape == (20 * 4 ** 2, 3, 3)  # an icosahedron's 20 faces, each split in 4 per subdivision
    embree = embree_side.load_embree()
    if with_embree and embree[0] is None:
        pytest.skip(f"embreex is not installed ({embree[2]}): `pip install -e \".[test]\"` (or `.[bench]`) installs "
                    "it; scripts/setup.sh does")
    if not with_embree:
        embree = (None, None, "not asked for")
    pool = None
    if embree[0] is not None:
        from concurrent.futures import ThreadPoolExecutor
        pool = ThreadPoolExecutor(2)
    try:
        res = bvh_measure.measure_mesh(TINY.name, tris, tiny_config(), embree if embree[0] is not None else None, pool,
                               log=lambda *a: None)
    finally:
        if pool is not None:
            pool.shutdown()
    assert res["triangles"] == 320
    assert [b["strategy"] for b in res["builds"]] == ["sah", "midpoint"]
    for b in res["builds"]:
        assert b["seconds"] > 0 and b["triangles_per_s"] > 0 and b["sah_cost"] > 0 and b["nodes"] >= 1
        db = b["device_bytes"]
        assert db["total"] == db["bvh"] + db["triangles"] and db["per_triangle"] == pytest.approx(db["total"] / 320)
        assert db["triangles"] == 320 * 9 * 4  # three corners of three f32 per triangle
    assert len(res["configs"]) == 4
    for c in res["configs"]:
        for kind in ("coherent", "incoherent"):
            s = c[kind]
            assert s["mrays_per_s"] > 0 and s["nodes_per_ray"] >= 1 and 0 < s["hit_fraction"] <= 1
    # rays from outside aimed into the box of a closed sphere: every one that enters it far enough hits
    assert res["configs"][0]["incoherent"]["tests_per_ray"] > 0
    sh = res["shadow"]
    assert 0 < sh["occluded_fraction"] < 1 and sh["consistent_with_closest"] == 1.0
    if embree[0] is not None:
        assert res["embree"]["available"] and res["embree"]["incoherent"]["mrays_per_s"] > 0
        assert res["agreement_all_configs"]["incoherent"] >= 0.99
        assert res["ratio_to_embree"]["incoherent"]["default"] > 0
        assert sh["agreement_with_embree"] >= 0.99
    else:
        assert res["embree"] == {"available": False}
    path = write_json(tmp_path / "mesh.json", res)
    assert json.loads(path.read_text())["configs"][0]["strategy"] == "sah"


def test_run_without_embree(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(embree_side, "load_embree", lambda: (None, None, "ImportError: not here"))
    assert bvh.run(out_dir=tmp_path, config=tiny_config(strategies=("sah",), traversals=("stack",))) == 0
    out = capsys.readouterr().out
    assert "Embree columns are skipped" in out and "Targets:" in out
    report = json.loads((tmp_path / "bench_bvh.json").read_text())
    assert report["embree"]["available"] is False
    assert report["meshes"][0]["name"] == TINY.name
    assert [r["max_leaf_size"] for r in report["leaf_size"]["rows"]] == [2, 4]
    leaf = report["leaf_size"]
    best = max(leaf["rows"], key=lambda r: r["incoherent"]["mrays_per_s"])
    assert leaf["best_max_leaf_size"] == best["max_leaf_size"] and best["max_leaf_size"] in leaf["within_tie_of_best"]
    assert report["threads"]["taichi"] >= 1
    for name in report["plots"]:
        assert (tmp_path / name).stat().st_size > 0

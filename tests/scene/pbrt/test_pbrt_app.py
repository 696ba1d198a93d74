"""`python app.py info` on a .pbrt file: the command line dispatches the suffix to the reader
(renderer/scene/catalog.py)."""
from __future__ import annotations

import gzip
import subprocess
import sys
from pathlib import Path

from renderer.scene.catalog import load_any

from tests.scene.pbrt.pbrt_helpers import CAMERA, SPHERE, write

ROOT = Path(__file__).resolve().parents[3]


def test_load_any_dispatches_pbrt(tmp_path):
    path = write(tmp_path, CAMERA + "WorldBegin\n" + SPHERE)
    assert load_any(path).description == "pbrt-v4 scene s.pbrt"


def test_load_any_reads_gzipped_scenes(tmp_path):
    path = tmp_path / "s.pbrt.gz"
    path.write_bytes(gzip.compress((CAMERA + "WorldBegin\n" + SPHERE).encode()))
    scene = load_any(path)
    assert scene.name == "s" and [o.kind for o in scene.mesh_objects] == ["sphere"]


def test_app_info_on_a_pbrt_file(tmp_path):
    path = write(tmp_path, CAMERA + "WorldBegin\nMaterial \"conductor\"\n" + SPHERE)
    result = subprocess.run([sys.executable, str(ROOT / "app.py"), "info", str(path)], capture_output=True,
                            text=True, timeout=120, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    assert "conductor" in result.stdout and "16" in result.stdout

"""A scene's files shipped to workers: every file it reads, read in place or unpacked elsewhere."""
import shutil
from pathlib import Path

import numpy as np

from renderer.commands.distributed.bundle import SceneBundle
from renderer.mesh_world import prepare_mesh_scene
from renderer.scene.catalog import load_any, resolve_scene

ROOT = Path(__file__).resolve().parents[3]


def test_a_scene_with_models_unpacks_elsewhere_and_loads_the_same(tmp_path):
    scene = load_any(resolve_scene("bunnies"))
    bundle = SceneBundle.of(scene)
    assert set(bundle.files) == {"scenes/bunnies.toml", "models/bunny.glb", "envmaps/sky.exr"}
    assert bundle.in_place() == Path(scene.path).resolve()
    copy = load_any(bundle.unpack(tmp_path))
    assert np.array_equal(prepare_mesh_scene(copy).data.tri_vertices, prepare_mesh_scene(scene).data.tri_vertices)


def test_an_obj_model_takes_its_material_library_and_textures(tmp_path):
    for name in ("materials.obj", "materials.mtl", "checker.png"):
        shutil.copy(ROOT / "tests" / "data" / name, tmp_path / name)
    scene = load_any(tmp_path / "materials.obj")
    bundle = SceneBundle.of(scene)
    # (and the default environment map a model opened as a scene is lit by)
    names = {Path(name).name for name in bundle.files}
    assert {"materials.obj", "materials.mtl", "checker.png"} < names and len(names) == 4
    (tmp_path / "checker.png").write_bytes(b"changed")  # a node whose copy differs unpacks its own
    assert bundle.in_place() is None
    unpacked = bundle.unpack(tmp_path / "elsewhere")
    assert (unpacked.parent / "checker.png").read_bytes() == (ROOT / "tests" / "data" / "checker.png").read_bytes()

"""Edits of a model file's own materials (glTF's): a factor edit in a rendering Renderer is the
edited scene's image bit for bit from the same programs; a pick names the model material and its
panel edits it; the edits are saved as [model_materials.<i>] (in a TOML scene's copy, or in a scene
of edits beside a model opened by itself) and read back as the same image; bad tables are one line."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.editing import ModelMaterialEdit, clamped, with_model_material
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any
from renderer.scene.edit_saving import save_edits
from renderer.scene.errors import SceneError
from tests.render.test_material_edits import kernels_compiled

DATA = Path(__file__).resolve().parents[1] / "data"
SIZE = (16, 16)
GREEN = ModelMaterialEdit(2, (("base_color_factor", (0.1, 0.9, 0.2)), ("roughness_factor", 0.2)))


@pytest.fixture
def quads(tmp_path):
    path = tmp_path / "colored_quads.gltf"
    shutil.copy(DATA / "colored_quads.gltf", path)
    return load_any(path)


def render(renderer):
    renderer.render(CameraFrame.from_spec(renderer.scene.camera), 2, "mis", seed=6)
    return renderer.image()


def test_a_model_material_edit_is_the_edited_scenes_image_and_compiles_nothing(quads):
    renderer = Renderer(quads, max_size=SIZE)
    before = render(renderer)
    compiled, programs = kernels_compiled(), dict(renderer._programs)
    edited = with_model_material(quads, GREEN)
    assert renderer.edit_materials(edited)
    after = render(renderer)
    assert kernels_compiled() == compiled and renderer._programs == programs and not np.array_equal(before, after)
    assert renderer.model_material(2).pbr.base_color_factor == (0.1, 0.9, 0.2, 1.0)
    assert renderer.model_material(2).file_pbr.base_color_factor == (0.3, 0.6, 0.9, 1.0)
    np.testing.assert_array_equal(after, render(Renderer(edited, max_size=SIZE)))
    assert renderer.edit_materials(quads)  # undone: the file's material again
    np.testing.assert_array_equal(render(renderer), before)


def test_a_picked_model_material_is_edited_by_its_panel_and_saved_beside_the_model(quads, tmp_path):
    from tests.viewer.test_material_panel import FakeGui
    from viewer.model_material_panel import draw_model_material_panel
    from viewer.scene_editor import SceneEditor

    renderer = Renderer(quads, max_size=SIZE)
    editor = SceneEditor(quads, lambda s: pytest.fail("a factor needs no new renderer"))
    picked = editor.pick(renderer, CameraFrame.from_spec(quads.camera), 0.5, 0.5)
    assert picked is not None and picked.model_material >= 0 and picked.material_name.startswith("model material")
    gui = FakeGui(values={"metallic": 1.0, "base_color": (1.0, 0.766, 0.336)})
    edit, actions = draw_model_material_panel(gui, (960, 540), picked, renderer.model_material(picked.model_material))
    assert actions == [] and "roughness [0, 1]" in gui.drawn and dict(edit.changes)["metallic_factor"] == 1.0
    untouched, _ = draw_model_material_panel(FakeGui(), (960, 540), picked, renderer.model_material(picked.model_material))
    assert untouched is None
    editor.apply(renderer, edit)
    assert renderer.scene.model_material_edits == ((picked.model_material, edit.changes),)
    saved = editor.save(renderer.scene)
    assert saved == tmp_path / "colored_quads_edited.toml"
    assert f"[model_materials.{picked.model_material}]" in saved.read_text() and "metallic = 1.0" in saved.read_text()
    again = load_any(saved)
    assert again.model_material_edits == renderer.scene.model_material_edits
    np.testing.assert_array_equal(render(renderer), render(Renderer(again, max_size=SIZE)))
    editor.reset_material(renderer)
    assert renderer.scene.model_material_edits == ()


def test_a_toml_scenes_model_material_edits_are_saved_in_its_copy(tmp_path):
    shutil.copy(DATA / "colored_quads.gltf", tmp_path / "quads.gltf")
    path = tmp_path / "room.toml"
    path.write_text('[scene]\ngeometry = "mesh"\n[camera]\nposition = [0, 2, 10]\n[[objects]]\ntype = "mesh"\n'
                    'file = "quads.gltf"\n')
    loaded = load_any(path)
    edited = with_model_material(loaded, GREEN)
    again = load_any(save_edits(edited, loaded))
    assert again.model_material_edits == edited.model_material_edits
    np.testing.assert_array_equal(render(Renderer(edited, max_size=SIZE)), render(Renderer(again, max_size=SIZE)))
    fixed, notes = clamped(ModelMaterialEdit(0, (("ior", 9.0), ("metallic_factor", -1.0))))
    assert dict(fixed.changes) == {"ior": 4.0, "metallic_factor": 0.0} and len(notes) == 2


@pytest.mark.parametrize("table, problem", [
    ("[model_materials.9]\nroughness = 0.5", "model_materials.9: the scene's model files bring 3 materials"),
    ("[model_materials.first]\nroughness = 0.5", "model_materials.first: expected a model material's number"),
    ("[model_materials.0]\nroughnes = 0.5", "model_materials.0: unknown field 'roughnes'"),
    ("[model_materials.0]\nmetallic = 2", "model_materials.0.metallic: 2 is out of range"),
])
def test_a_bad_model_material_table_is_one_line(tmp_path, table, problem):
    shutil.copy(DATA / "colored_quads.gltf", tmp_path / "quads.gltf")
    path = tmp_path / "bad.toml"
    path.write_text('[scene]\nedits = "quads.gltf"\n' + table + "\n")
    with pytest.raises(SceneError, match=problem) as error:
        Renderer(load_any(path), max_size=SIZE)
    assert str(path) in str(error.value) and "\n" not in str(error.value)

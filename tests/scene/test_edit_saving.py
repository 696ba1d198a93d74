"""Edited materials saved into a TOML scene: every material of the shipped scenes reads back as
itself, the edited file keeps the rest of the original's text, renders as the edited scene bit for
bit, and what TOML cannot say or where it may not go is one line."""
from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from renderer.scene import SceneError, load_scene
from renderer.scene.description import MaterialSpec, TextureSpec
from renderer.scene.edit_saving import edited_path, material_table, save_edits

REPO = Path(__file__).resolve().parents[2]
SCENES = sorted(p for p in (REPO / "assets" / "scenes").glob("*.toml") if "[materials." in p.read_text())


def toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value + '"'
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return repr(value)


@pytest.mark.parametrize("path", SCENES, ids=[p.stem for p in SCENES])
def test_every_shipped_material_reads_back_as_itself(tmp_path, path):
    scene = load_scene(path)
    text = [f'[scene]\ngeometry = "{scene.geometry}"\n']
    for spec in scene.materials:
        text.append(f"[materials.{spec.name}]")
        text += [f"{k} = {toml_value(v)}" for k, v in material_table(spec, tmp_path).items()]
    media = path.read_text().split("[media.")  # the media the materials name, as the file has them
    text += ["[media." + m.split("\n[[")[0].split("\n[materials")[0] for m in media[1:]]
    first = scene.materials[0].name
    text.append('[[objects]]\ntype = "sphere"\nmaterial = "' + first + '"')
    out = tmp_path / "again.toml"
    out.write_text("\n".join(text) + "\n")
    assert load_scene(out).materials == scene.materials


def test_an_edited_cornell_box_is_saved_beside_it_and_renders_as_edited(tmp_path):
    from renderer.camera import CameraFrame
    from renderer.editing import canonical, material_named, with_material
    from renderer.renderer import Renderer

    original = tmp_path / "cornell_box.toml"
    shutil.copy(REPO / "assets" / "scenes" / "cornell_box.toml", original)
    loaded = load_scene(original)
    gold = canonical(replace(material_named(loaded, "tall_box"), kind="conductor", metal="Au", roughness=0.25))
    edited = with_material(loaded, gold)
    saved = save_edits(edited, loaded)
    assert saved == tmp_path / "cornell_box_edited.toml" == edited_path(original)
    text = saved.read_text()
    assert "# The Cornell box of Mitsuba 3's" in text and 'metal = "Au"' in text  # the rest kept as written
    again = load_scene(saved)
    assert again.materials == edited.materials and again.mesh_objects == loaded.mesh_objects

    def render(scene):
        r = Renderer(scene, max_size=(16, 16))
        r.render(CameraFrame.from_spec(scene.camera), 2, "mis", seed=3)
        return r.image()

    live = Renderer(loaded, max_size=(16, 16))
    assert live.edit_materials(edited)
    live.render(CameraFrame.from_spec(edited.camera), 2, "mis", seed=3)
    np.testing.assert_array_equal(live.image(), render(again))
    assert save_edits(edited, loaded) == saved  # saving again replaces the edited file


def test_what_may_not_be_saved_is_one_line(tmp_path):
    original = tmp_path / "cornell_box.toml"
    shutil.copy(REPO / "assets" / "scenes" / "cornell_box.toml", original)
    loaded = load_scene(original)
    with pytest.raises(SceneError, match="saving over it must be asked for"):
        save_edits(loaded, loaded, path=original)
    assert save_edits(loaded, loaded, path=original, overwrite=True) == original
    (tmp_path / "elsewhere").mkdir()
    with pytest.raises(SceneError, match="in its original's folder"):
        save_edits(loaded, loaded, path=tmp_path / "elsewhere" / "x.toml")
    textured = replace(loaded.materials[0], base_color_texture=TextureSpec("checkerboard"))
    with pytest.raises(SceneError, match="material 'white': its base_color_texture cannot be written"):
        material_table(textured, tmp_path)
    assert material_table(MaterialSpec("m"), tmp_path) == {"type": "diffuse", "roughness": 0.5}

"""Edits of a Mitsuba or pbrt scene saved as a TOML scene of edits: the file it edits referenced,
only the changed values written, the saved file read back as the edited scene and rendered as the
viewer showed it bit for bit; a scene of edits opened, edited again and saved; bad files one line."""
from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from renderer.editing import canonical, material_named, with_material
from renderer.scene.catalog import load_any
from renderer.scene.description import TextureSpec
from renderer.scene.edit_saving import edited_path, save_edits
from renderer.scene.errors import SceneError
from tests.scene.pbrt.pbrt_helpers import CAMERA, write

MITSUBA = Path(__file__).resolve().parents[1] / "data" / "mitsuba"


@pytest.fixture
def cornell(tmp_path):
    """The Mitsuba Cornell box (and its files) copied into tmp_path, loaded."""
    for file in MITSUBA.iterdir():
        if file.is_file():
            shutil.copy(file, tmp_path / file.name)
    return load_any(tmp_path / "cornell_box.xml")


def gold(scene, name):
    return canonical(replace(material_named(scene, name), kind="conductor", metal="Au", roughness=0.2))


def test_a_mitsuba_scenes_edits_are_saved_as_the_changes_to_its_file(cornell, tmp_path):
    edited = with_material(cornell, gold(cornell, "red"))
    edited = replace(edited, environment=replace(edited.environment, color=(0.1, 0.2, 0.3)))
    saved = save_edits(edited, cornell)
    assert saved == tmp_path / "cornell_box_edited.toml" == edited_path(tmp_path / "cornell_box.xml")
    text = saved.read_text()
    assert 'edits = "cornell_box.xml"' in text and 'metal = "Au"' in text
    assert "base_color" not in text and "[materials.white]" not in text  # only what changed
    back = load_any(saved)
    assert back.materials == edited.materials and back.environment == edited.environment
    assert back.mesh_objects == cornell.mesh_objects and back.camera == cornell.camera
    assert back.path == saved and tmp_path / "cornell_box.xml" in back.source_files
    assert (tmp_path / "cornell_box.xml").read_text() == (MITSUBA / "cornell_box.xml").read_text()


def test_the_saved_scene_of_edits_renders_as_the_viewer_showed_it(cornell):
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    edited = with_material(cornell, gold(cornell, "green"))
    live = Renderer(cornell, max_size=(16, 16))
    assert live.edit_materials(edited)  # in place, as in the viewer
    live.render(CameraFrame.from_spec(edited.camera), 2, "mis", seed=3)
    again = load_any(save_edits(edited, cornell))
    saved = Renderer(again, max_size=(16, 16))
    saved.render(CameraFrame.from_spec(again.camera), 2, "mis", seed=3)
    np.testing.assert_array_equal(live.image(), saved.image())
    assert not np.array_equal(live.image(), _render(cornell))  # the edit shows


def _render(scene):
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    r = Renderer(scene, max_size=(16, 16))
    r.render(CameraFrame.from_spec(scene.camera), 2, "mis", seed=3)
    return r.image()


def test_a_scene_of_edits_edited_again_keeps_the_earlier_edits(cornell, tmp_path):
    first = load_any(save_edits(with_material(cornell, gold(cornell, "red")), cornell))
    rough = replace(material_named(first, "white"), roughness=0.9)
    second = with_material(first, rough)
    out = save_edits(second, first, path=tmp_path / "second.toml")
    back = load_any(out)
    assert material_named(back, "red") == gold(cornell, "red") and material_named(back, "white") == rough
    assert back.edited_from.path == tmp_path / "cornell_box.xml"  # edits of the file, not of the edits
    undone = with_material(second, material_named(cornell, "red"))
    assert "[materials.red]" not in (save_edits(undone, back, path=out, overwrite=True)).read_text()


def test_a_pbrt_scenes_edits(tmp_path):
    path = write(tmp_path, CAMERA + 'WorldBegin\nMakeNamedMaterial "glass" "string type" "dielectric" "float eta" 1.5\n'
                 'NamedMaterial "glass"\nShape "sphere" "float radius" [0.5]\n', name="ball.pbrt")
    loaded = load_any(path)
    glass = replace(material_named(loaded, "glass"), ior=1.33, roughness=0.1)
    saved = save_edits(with_material(loaded, glass), loaded)
    assert saved.name == "ball_edited.toml"
    assert material_named(load_any(saved), "glass") == glass
    assert edited_path(tmp_path / "x.pbrt.gz").name == "x_edited.toml"


def test_a_conductors_fresnel_written_replaces_the_files(tmp_path):
    path = write(tmp_path, CAMERA + 'WorldBegin\nMakeNamedMaterial "m" "string type" "conductor" '
                 '"spectrum eta" "metal-Cu-eta" "spectrum k" "metal-Cu-k"\nNamedMaterial "m"\n'
                 'Shape "sphere" "float radius" [0.5]\n', name="cu.pbrt")
    loaded = load_any(path)
    assert material_named(loaded, "m").metal or material_named(loaded, "m").eta is not None
    for edit in (dict(metal="Ag"), dict(metal="", eta=(0.2, 0.9, 1.1), k=(3.9, 2.4, 2.1)),
                 dict(metal="", eta=None, k=None, base_color=(0.9, 0.5, 0.3))):
        spec = canonical(replace(material_named(loaded, "m"), **edit))
        out = save_edits(with_material(loaded, spec), loaded)
        assert material_named(load_any(out), "m") == spec, edit


def test_what_a_scene_of_edits_cannot_say_is_one_line(cornell, tmp_path):
    textured = replace(material_named(cornell, "white"), base_color_texture=TextureSpec("checkerboard"))
    with pytest.raises(SceneError, match="material 'white': its base_color_texture cannot be written"):
        save_edits(with_material(cornell, textured), cornell)
    moved = replace(cornell, camera=replace(cornell.camera, fov=20.0))
    with pytest.raises(SceneError, match="its camera changed too"):
        save_edits(moved, cornell)
    assert not (tmp_path / "cornell_box_edited.toml").exists()


@pytest.mark.parametrize("text, problem", [
    ('[scene]\nedits = "nothere.xml"\n', "scene.edits: .*nothere.xml"),
    ('[scene]\nedits = "other.toml"\n', r"is not a Mitsuba .* \(a TOML scene's edits are saved in a copy"),
    ('[scene]\nedits = "cornell_box.xml"\ngeometry = "mesh"\n', "scene.geometry: not part of a scene of edits"),
    ('[scene]\nedits = "cornell_box.xml"\n[camera]\nfov = 30\n', "section 'camera' is not part of a scene of edits"),
    ('[scene]\nedits = "cornell_box.xml"\n[materials.gold]\nroughness = 0.5\n',
     "materials.gold: the edited scene has no material 'gold' .*green, red, white"),
    ('[scene]\nedits = "cornell_box.xml"\n[materials.red]\nroughnes = 0.5\n', "materials.red: unknown field 'roughnes'"),
    ('[scene]\nedits = "cornell_box.xml"\n[materials.red]\nroughness = 1.5\n', "materials.red.roughness: 1.5 is out of range"),
    ('[scene]\nedits = "cornell_box.xml"\n[materials.red]\nmetal = "Au"\n', "materials.red.metal: only allowed with type 'conductor'"),
    ('[scene]\nedits = "cornell_box.xml"\n[materials.red]\ntype = "conductor"\nmetal = "Au"\nbase_color = [1, 0, 0]\n',
     "cannot be combined"),
    ('[scene]\nedits = "cornell_box.xml"\n[environment]\ntype = "sky"\n', "environment.type: a scene of edits keeps"),
    ('[scene]\nedits = "cornell_box.xml"\n[lights.0]\nintensity = [1, 1, 1]\n', "lights.0: the edited scene has no lights"),
])
def test_a_bad_scene_of_edits_is_one_line_naming_it(cornell, tmp_path, text, problem):
    (tmp_path / "other.toml").write_text('[scene]\ngeometry = "mesh"\n')
    path = tmp_path / "edits.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match=problem) as error:
        load_any(path)
    assert str(path) in str(error.value) and "\n" not in str(error.value)


def test_the_plain_toml_reader_points_a_scene_of_edits_to_the_catalog(cornell, tmp_path):
    from renderer.scene import load_scene

    path = tmp_path / "edits.toml"
    path.write_text('[scene]\nedits = "cornell_box.xml"\n')
    assert load_any(path).materials == cornell.materials
    with pytest.raises(SceneError, match="opened with renderer.scene.catalog.load_any"):
        load_scene(path)


def test_a_pbrt_scenes_light_edits_and_bad_light_tables(tmp_path):
    from renderer.editing import SceneLight, clamped, with_light

    path = write(tmp_path, CAMERA + 'WorldBegin\nLightSource "spot" "point3 from" [0 2 0] "point3 to" [0 0 0] '
                 '"float coneangle" [30] "blackbody I" [3000]\nLightSource "point" "point3 from" [1 1 1]\n'
                 + 'Shape "sphere" "float radius" [0.5]\n', name="lamps.pbrt")
    loaded = load_any(path)
    spot, _ = clamped(SceneLight(0, replace(loaded.lights[0], cutoff_angle=40.0, position=(0.0, 3.0, 0.5))))
    edited = with_light(loaded, spot)
    saved = save_edits(edited, loaded)
    assert load_any(saved).lights == edited.lights and "[lights.1]" not in saved.read_text()
    for table, problem in (("[lights.2]\nintensity = [1, 1, 1]", r"lights.2: the edited scene has 2 lights \(lights.0 to lights.1\)"),
                           ('[lights.0]\ntype = "point"', "lights.0.type: a scene of edits keeps the light's type"),
                           ("[lights.1]\ncutoff_angle = 10", "lights.1.cutoff_angle: only allowed with type 'spot'"),
                           ("[lights.0]\nbeam_width = 50", "beam_width")):
        bad = tmp_path / "bad.toml"
        bad.write_text('[scene]\nedits = "lamps.pbrt"\n' + table + "\n")
        with pytest.raises(SceneError, match=problem):
            load_any(bad)

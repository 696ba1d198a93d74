"""Editing in the viewer, headless: a click on the Cornell box's tall box opens its material, an
edit shows at once (the same Renderer, nothing rebuilt), undo and redo walk the history, a texture
change builds a Renderer anew, and ctrl+s saves the edited scene beside its file, which renders
as the viewer showed it."""
from __future__ import annotations

import math
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.editing import material_named
from renderer.renderer import Renderer
from renderer.scene import load_scene
from renderer.scene.description import TextureSpec
from viewer.scene_editor import SceneEditor
from viewer.window import FrameInput, ViewerApp

REPO = Path(__file__).resolve().parents[2]
SIZE = (64, 64)
GOLD = dict(kind="conductor", metal="Au", roughness=0.2)


def tall_box_cursor(scene):
    """Where the window shows the tall box's front (GGUI's cursor: [0,1]^2, y up)."""
    half = math.tan(math.radians(scene.camera.fov) / 2) * scene.camera.position[2]
    return 0.5 - 0.33 / (2 * half), 0.5 - 0.4 / (2 * half)


@pytest.fixture(scope="module")
def viewer(tmp_path_factory):
    """One window for the module (GGUI keeps each window's device objects for the process): each
    test shows its own scene file in it (ViewerApp.select_scene)."""
    first = tmp_path_factory.mktemp("viewer") / "cornell_box.toml"
    shutil.copy(REPO / "assets" / "scenes" / "cornell_box.toml", first)
    return ViewerApp(first, size=SIZE, show_window=False, scenes=[first], settle_seconds=0.0,
                     still_present_interval=0.0)


def showing(viewer, path):
    """The viewer showing `path`, its HUD hidden (at 64x64 it would cover the box, and a click there
    is the HUD's)."""
    viewer.select_scene(path)
    viewer.session.hud_visible = False
    viewer.step()
    return viewer


@pytest.fixture
def cornell(tmp_path):
    path = tmp_path / "cornell_box.toml"
    shutil.copy(REPO / "assets" / "scenes" / "cornell_box.toml", path)
    return path


def test_the_editor_applies_undoes_redoes_resets_and_rebuilds(cornell):
    scene = load_scene(cornell)
    renderer = Renderer(scene, max_size=(16, 16))
    built = []
    editor = SceneEditor(scene, lambda s: built.append(Renderer(s, max_size=(16, 16))) or built[-1])
    picked = editor.pick(renderer, CameraFrame.from_spec(scene.camera), *tall_box_cursor(scene))
    assert picked.material_name == "tall_box"
    box = editor.picked_material(renderer.scene)
    assert editor.apply(renderer, replace(box, **GOLD)) is renderer and not editor.recompiled
    assert material_named(renderer.scene, "tall_box").metal == "Au"
    editor.apply(renderer, replace(material_named(renderer.scene, "tall_box"), roughness=7.0))
    assert material_named(renderer.scene, "tall_box").roughness == 1.0 and "allowed [0, 1]" in editor.notes[0]
    editor.undo(renderer)
    assert material_named(renderer.scene, "tall_box").roughness == 0.2
    editor.undo(renderer)
    assert material_named(renderer.scene, "tall_box") == box
    editor.redo(renderer)
    assert material_named(renderer.scene, "tall_box").metal == "Au"
    editor.reset_material(renderer)
    assert material_named(renderer.scene, "tall_box") == box and editor.history.undo() is not None
    checks = TextureSpec("checkerboard", color0=(1, 1, 1), color1=(0, 0, 0), nearest=True)
    rebuilt = editor.apply(renderer, replace(box, base_color_texture=checks))
    assert rebuilt is built[0] and editor.recompiled and rebuilt.scene.materials != renderer.scene.materials


def test_click_edit_undo_and_save_in_the_window(viewer, cornell):
    app = showing(viewer, cornell)
    for _ in range(2):
        app.step()
    cursor = tall_box_cursor(app.renderer.scene)
    app.step(FrameInput(cursor=cursor, pressed=("LMB",), released=("LMB",)))  # a click within one frame
    assert app.editor.picked is not None and app.editor.picked.material_name == "tall_box"
    mask, _ = app.highlight  # the picked quad's pixels, tinted for a moment
    w, h = mask.shape
    assert mask[int(cursor[0] * w), int(cursor[1] * h)] and 0 < mask.sum() < 0.1 * mask.size
    renderer = app.renderer
    box = app.editor.picked_material(renderer.scene)
    app.edit(lambda r: app.editor.apply(r, replace(box, **GOLD)), 0.0)
    for _ in range(40):  # the conductor's kernel compiles (a notice first), then the image converges again
        app.step()
        if renderer.samples_done >= 2:
            break
    assert app.renderer is renderer and material_named(renderer.scene, "tall_box").metal == "Au"
    assert renderer.samples_done >= 2 and "conductor" in renderer.features().material_kinds
    app.step(FrameInput(pressed=("ctrl+z",)))
    assert material_named(app.renderer.scene, "tall_box") == box
    app.step(FrameInput(pressed=("ctrl+y",)))
    resets = app.session.resets
    app.step(FrameInput(pressed=("ctrl+y",)))  # nothing left to redo: the image goes on converging
    assert app.session.resets == resets
    app.step(FrameInput(pressed=("ctrl+s",)))
    saved = cornell.with_name("cornell_box_edited.toml")
    assert app.last_saved == saved and load_scene(saved).materials == app.renderer.scene.materials
    assert app.renderer.scene.camera == load_scene(saved).camera
    app.session.hud_visible = True  # the material panel drawn by GGUI itself, beside the HUD
    app.step()
    assert app.session.error is None and app.editor.picked is not None


def test_a_tint_goes_halfway_to_the_highlight_colour_on_the_mask_only():
    from viewer.display import HIGHLIGHT_COLOUR, tinted

    packed = np.full((3, 2), 0xFF000000 | (200 << 16) | (100 << 8) | 50, np.uint32)  # R 50, G 100, B 200
    mask = np.zeros((3, 2), bool)
    mask[1, 0] = True
    out = tinted(packed, mask)
    channels = out.view(np.uint8).reshape(3, 2, 4)
    assert tuple(channels[1, 0, :3]) == tuple((np.array([50, 100, 200]) + HIGHLIGHT_COLOUR) // 2)
    assert (out[~mask] == packed[~mask]).all() and (packed[1, 0] != out[1, 0])


def test_a_click_on_nothing_opens_the_environment_whose_edits_save(tmp_path):
    from tests.render.test_material_edits import SKY_SCENE

    path = tmp_path / "sky.toml"
    path.write_text(SKY_SCENE + "# the end of the file, kept\n")
    scene = load_scene(path)
    renderer = Renderer(scene)
    editor = SceneEditor(scene, lambda s: pytest.fail("an environment's intensity needs no new renderer"))
    assert editor.pick(renderer, CameraFrame.from_spec(scene.camera), 0.02, 0.98) is None
    assert editor.environment_open
    editor.apply(renderer, replace(scene.environment, intensity=3.0, rotation=400.0))
    assert renderer.scene.environment.intensity == 3.0
    editor.apply(renderer, replace(renderer.scene.environment, intensity=-1.0))
    assert renderer.scene.environment.intensity == 0.0 and "intensity -1 -> 0" in editor.notes[0]
    editor.undo(renderer)
    saved = editor.save(renderer.scene)
    again = load_scene(saved)
    assert again.environment == renderer.scene.environment and again.environment.intensity == 3.0
    assert "# the end of the file, kept" in saved.read_text()
    editor.reset_material(renderer)  # the environment panel is open: back to the file's
    assert renderer.scene.environment == scene.environment


def test_a_mitsuba_scenes_edits_save_as_a_scene_of_edits_that_renders_as_shown(viewer, tmp_path):
    from renderer.scene.catalog import load_any

    for file in (REPO / "tests" / "data" / "mitsuba").iterdir():
        if file.is_file():
            shutil.copy(file, tmp_path / file.name)
    xml = tmp_path / "cornell_box.xml"
    app = showing(viewer, xml)
    app.step(FrameInput(cursor=tall_box_cursor(app.renderer.scene), pressed=("LMB",), released=("LMB",)))
    assert app.editor.picked.material_name == "white"  # the Mitsuba file's boxes share the walls' BSDF
    white = app.editor.picked_material(app.renderer.scene)
    app.edit(lambda r: app.editor.apply(r, replace(white, base_color=(0.2, 0.3, 0.9))), 0.0)
    app.step(FrameInput(pressed=("ctrl+s",)))
    saved = tmp_path / "cornell_box_edited.toml"
    assert app.last_saved == saved and app.session.error is None
    again = load_any(saved)
    assert again.materials == app.renderer.scene.materials and again.edited_from.path == xml

    def image(renderer):
        renderer.render(CameraFrame.from_spec(renderer.scene.camera), 2, "mis", seed=9)
        return renderer.image()

    shown = Renderer(load_any(xml), max_size=(16, 16))
    assert shown.edit_materials(app.renderer.scene)
    np.testing.assert_array_equal(image(shown), image(Renderer(again, max_size=(16, 16))))


def test_a_light_edited_from_the_environments_panel_undoes_resets_and_saves(tmp_path):
    from renderer.editing import SceneLight
    from tests.render.test_light_edits import LAMPS

    path = tmp_path / "lamps.toml"
    path.write_text(LAMPS + "# the end of the file, kept\n")
    scene = load_scene(path)
    renderer = Renderer(scene, max_size=(16, 16))
    editor = SceneEditor(scene, lambda s: pytest.fail("a light's values need no new renderer"))
    editor.open_light(1)
    assert editor.panel_open and editor.light_open == 1 and editor.picked is None
    spot = SceneLight(1, scene.lights[1])
    editor.apply(renderer, replace(spot, spec=replace(spot.spec, cutoff_angle=400.0, beam_width=500.0)))
    assert renderer.scene.lights[1].cutoff_angle < 180.0 and renderer.scene.lights[1].beam_width == renderer.scene.lights[1].cutoff_angle
    assert any("cutoff_angle 400" in n for n in editor.notes) and any("at most cutoff_angle" in n for n in editor.notes)
    editor.undo(renderer)
    assert renderer.scene.lights == scene.lights
    brighter = replace(spot, spec=replace(spot.spec, intensity=(40.0, 36.0, 30.0), position=(-0.5, 2.5, 0.5)))
    editor.apply(renderer, brighter)
    saved = editor.save(renderer.scene)
    again = load_scene(saved)
    assert again.lights == renderer.scene.lights and "# the end of the file, kept" in saved.read_text()
    editor.reset_material(renderer)  # the light's panel is open: back to the file's
    assert renderer.scene.lights == scene.lights


def test_a_mitsuba_scenes_light_edits_save_as_a_scene_of_edits(tmp_path):
    from renderer.editing import SceneLight
    from renderer.scene.catalog import load_any

    xml = tmp_path / "spot.xml"
    xml.write_text('''<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 2, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
    </sensor>
    <emitter type="spot"><rgb name="intensity" value="10"/><float name="cutoff_angle" value="25"/>
        <transform name="to_world"><lookat origin="0, 3, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
    </emitter>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform></shape>
</scene>''')
    loaded = load_any(xml)
    renderer = Renderer(loaded, max_size=(16, 16))
    editor = SceneEditor(loaded, lambda s: pytest.fail("in place"))
    spot = SceneLight(0, loaded.lights[0])
    editor.apply(renderer, replace(spot, spec=replace(spot.spec, intensity=(5.0, 10.0, 20.0), cutoff_angle=35.0,
                                                      direction=(0.1, -1.0, 0.0))))
    saved = editor.save(renderer.scene)
    assert "[lights.0]" in saved.read_text() and "type" not in saved.read_text().split("[lights.0]")[1]
    again = load_any(saved)
    assert again.lights[0].intensity == (5.0, 10.0, 20.0) and again.lights[0].cutoff_angle == 35.0

    def image(r):
        r.render(CameraFrame.from_spec(r.scene.camera), 2, "mis", seed=2)
        return r.image()

    np.testing.assert_array_equal(image(renderer), image(Renderer(again, max_size=(16, 16))))


def test_the_light_panel_in_the_window(viewer, tmp_path):
    from renderer.editing import SceneLight
    from tests.render.test_light_edits import LAMPS

    path = tmp_path / "lamps.toml"
    path.write_text(LAMPS)
    app = showing(viewer, path)
    app.session.hud_visible = True
    app.dispatch("open_light:1", FrameInput(), 0.0)
    app.step()  # GGUI draws the light's panel
    renderer = app.renderer
    spot = SceneLight(1, renderer.scene.lights[1])
    app.edit(lambda r: app.editor.apply(r, replace(spot, spec=replace(spot.spec, intensity=(60.0, 50.0, 40.0)))), 0.0)
    app.step()
    assert app.renderer is renderer and renderer.scene.lights[1].intensity == (60.0, 50.0, 40.0)
    assert app.session.error is None and app.editor.light_open == 1
    app.dispatch("close_panel", FrameInput(), 0.0)
    assert not app.editor.panel_open


def test_a_model_files_material_in_the_window(viewer, tmp_path):
    from renderer.editing import ModelMaterialEdit

    path = tmp_path / "colored_quads.gltf"
    shutil.copy(REPO / "tests" / "data" / "colored_quads.gltf", path)
    app = showing(viewer, path)
    app.step(FrameInput(cursor=(0.5, 0.5), pressed=("LMB",), released=("LMB",)))
    picked = app.editor.picked
    assert picked is not None and picked.model_material >= 0
    app.step()  # GGUI draws the model material's panel
    renderer = app.renderer
    edit = ModelMaterialEdit(picked.model_material, (("roughness_factor", 0.1),))
    app.edit(lambda r: app.editor.apply(r, edit), 0.0)
    app.step()
    assert app.renderer is renderer and renderer.model_material(picked.model_material).pbr.roughness_factor == 0.1
    assert app.session.error is None
    app.step(FrameInput(pressed=("ctrl+s",)))
    assert app.last_saved == tmp_path / "colored_quads_edited.toml"


def test_a_saved_scene_opened_again_is_saved_over_on_a_second_ctrl_s(viewer, cornell):
    first = load_scene(cornell)
    saved = SceneEditor(first, None).save(first)  # cornell_box_edited.toml, as a first session saves it
    app = showing(viewer, saved)
    assert app.editor.saves_over_its_file
    box = material_named(app.renderer.scene, "tall_box")
    app.edit(lambda r: app.editor.apply(r, replace(box, base_color=(0.1, 0.2, 0.9))), 0.0)
    text = saved.read_text()
    assert app.save_edits(100.0) is None and saved.read_text() == text  # asked first
    assert "ctrl+s again to save over it" in app.session.current_message(100.0)
    assert app.save_edits(102.0) == saved and material_named(load_scene(saved), "tall_box").base_color == (0.1, 0.2, 0.9)
    assert app.save_edits(110.0) is None  # a later press asks again

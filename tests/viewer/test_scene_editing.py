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


def test_click_edit_undo_and_save_in_the_window(cornell):
    app = ViewerApp(cornell, size=SIZE, show_window=False, scenes=[cornell], settle_seconds=0.0,
                    still_present_interval=0.0)
    app.session.hud_visible = False  # at 64x64 the HUD would cover the box (a click there is the HUD's)
    for _ in range(3):
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


def test_a_mitsuba_scenes_edits_save_as_a_scene_of_edits_that_renders_as_shown(tmp_path):
    from renderer.scene.catalog import load_any

    for file in (REPO / "tests" / "data" / "mitsuba").iterdir():
        if file.is_file():
            shutil.copy(file, tmp_path / file.name)
    xml = tmp_path / "cornell_box.xml"
    app = ViewerApp(xml, size=SIZE, show_window=False, scenes=[xml], settle_seconds=0.0, still_present_interval=0.0)
    app.session.hud_visible = False
    app.step()
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

"""Editing materials while rendering (Renderer.edit_materials): an edit then a render gives, bit
for bit, the image of a renderer built on the edited scene; an edit of values compiles nothing,
an edit of kind compiles that kind once and undoing it compiles nothing; what needs the world
built again is refused without a change."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.editing import material_named, with_material
from renderer.program import RenderProgram
from renderer.renderer import Renderer
from renderer.scene import load_scene
from renderer.scene.description import TextureSpec
from tests.render.test_picking import BALL, sdf_scene

REPO = Path(__file__).resolve().parents[2]
SIZE = (16, 16)
GOLD = (1.0, 0.766, 0.336)


def kernels_compiled() -> int:
    """Render kernels instantiated in this process (one per program and launch signature)."""
    return len(RenderProgram._render._primal.compiled_kernels)


def image(renderer, scene, spp=2):
    renderer.render(CameraFrame.from_spec(scene.camera), spp, "mis", seed=7)
    return renderer.image()


@pytest.fixture(scope="module")
def cornell():
    return load_scene(REPO / "assets" / "scenes" / "cornell_box.toml")


def fresh(scene):
    return image(Renderer(scene, max_size=SIZE), scene)


def test_a_colour_edit_is_the_edited_scenes_image_and_compiles_nothing(cornell):
    renderer = Renderer(cornell, max_size=SIZE)
    before = image(renderer, cornell)
    compiled = kernels_compiled()
    edited = with_material(cornell, replace(material_named(cornell, "tall_box"), base_color=GOLD))
    assert renderer.edit_materials(edited)
    after = image(renderer, edited)
    assert kernels_compiled() == compiled and renderer.scene is edited
    assert not np.array_equal(before, after)
    np.testing.assert_array_equal(after, fresh(edited))


def test_a_kind_edit_compiles_the_kind_once_and_undoing_it_compiles_nothing(cornell):
    renderer = Renderer(cornell, max_size=SIZE)
    original = image(renderer, cornell)
    gold = with_material(cornell, replace(material_named(cornell, "tall_box"), kind="conductor", metal="Au",
                                          roughness=0.3))
    compiled = kernels_compiled()
    assert renderer.edit_materials(gold)
    assert "conductor" in renderer.features().material_kinds
    np.testing.assert_array_equal(image(renderer, gold), fresh(gold))
    assert renderer.edit_materials(cornell)  # undone: the diffuse-only kernel again
    assert "conductor" not in renderer.features().material_kinds
    compiled_after_kind = kernels_compiled()
    assert compiled_after_kind > compiled
    np.testing.assert_array_equal(image(renderer, cornell), original)
    # back to gold (its kernel is built), then an edit of roughness: nothing compiles
    rougher = with_material(gold, replace(material_named(gold, "tall_box"), roughness=0.6))
    assert renderer.edit_materials(gold) and renderer.edit_materials(rougher)
    edited = image(renderer, rougher)
    assert kernels_compiled() == compiled_after_kind
    np.testing.assert_array_equal(edited, fresh(rougher))


def test_an_emission_edit_relights_and_compiles_nothing(cornell):
    renderer = Renderer(cornell, max_size=SIZE)
    image(renderer, cornell)
    compiled, programs = kernels_compiled(), dict(renderer._programs)
    light = material_named(cornell, "light")
    brighter = with_material(cornell, replace(light, emission=tuple(2 * c for c in light.emission)))
    assert renderer.edit_materials(brighter)
    edited = image(renderer, brighter)
    assert kernels_compiled() == compiled and renderer._programs == programs  # the same programs, in place
    np.testing.assert_array_equal(edited, fresh(brighter))


TWO_LAMPS = """
[scene]
geometry = "mesh"
[camera]
position = [0, 1, 4]
look_at = [0, 0.5, 0]
fov = 50
[environment]
type = "constant"
color = [0.05, 0.05, 0.05]
[materials.floor]
base_color = [0.7, 0.7, 0.7]
[materials.warm]
emission = [4, 3, 2]
[materials.cool]
emission = [1, 2, 4]
[[objects]]
type = "quad"
material = "floor"
size = [6, 6]
[[objects]]
type = "sphere"
material = "warm"
translate = [-0.8, 0.6, 0]
radius = 0.25
[[objects]]
type = "sphere"
material = "cool"
translate = [0.8, 0.6, 0]
radius = 0.25
"""


@pytest.mark.parametrize("integrator", ["mis", "sppm"])
def test_an_emission_edit_reweighs_the_lights_in_place(tmp_path, integrator):
    """Two lamps (a power-weighted selector, and SPPM's photon emission): one made brighter is
    the edited scene's image, bit for bit, from the same programs; one turned off builds the lights
    again, and is still the edited scene's image."""
    path = tmp_path / "lamps.toml"
    path.write_text(TWO_LAMPS)
    scene = load_scene(path)

    def render(r, s):
        r.render(CameraFrame.from_spec(s.camera), 2, integrator, seed=5)
        return r.image()

    renderer = Renderer(scene, max_size=SIZE)
    render(renderer, scene)
    assert renderer.lights().selector.kind == "power"
    programs = dict(renderer._programs)
    warm = material_named(scene, "warm")
    brighter = with_material(scene, replace(warm, emission=(40.0, 30.0, 20.0)))
    assert renderer.edit_materials(brighter)
    np.testing.assert_array_equal(render(renderer, brighter), render(Renderer(brighter, max_size=SIZE), brighter))
    assert renderer._programs == programs
    dark = with_material(scene, replace(warm, emission=(0.0, 0.0, 0.0)))
    assert renderer.edit_materials(dark)
    np.testing.assert_array_equal(render(renderer, dark), render(Renderer(dark, max_size=SIZE), dark))
    assert renderer.lights().count == 1


def test_an_edit_that_needs_the_world_built_again_changes_nothing(cornell, tmp_path):
    renderer = Renderer(cornell, max_size=SIZE)
    checks = TextureSpec("checkerboard", color0=(1, 1, 1), color1=(0, 0, 0), nearest=True)
    textured = with_material(cornell, replace(material_named(cornell, "tall_box"), base_color_texture=checks))
    assert not renderer.edit_materials(textured) and renderer.scene is cornell
    with pytest.raises(ValueError, match="keeps the scene's materials"):
        renderer.edit_materials(replace(cornell, materials=cornell.materials[1:]))


def test_the_albedo_view_shows_a_named_metal_by_its_head_on_reflectance(cornell):
    """A conductor given by a named metal ignores its base colour: the albedo view (and the
    denoiser's guide) shows its reflectance at normal incidence, ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2)."""
    from renderer.editing import canonical
    from renderer.materials.conductor_ior import conductor_ior_row
    from tests.render.test_picking import screen_uv

    gold = canonical(replace(material_named(cornell, "tall_box"), kind="conductor", metal="Au"))
    scene = with_material(cornell, gold)
    renderer = Renderer(scene, max_size=(64, 64))
    renderer.render(CameraFrame.from_spec(scene.camera), 1, "albedo")
    u, v = screen_uv(scene, (-0.33, -0.4, 0.0))
    pixel = renderer.image()[int((1 - v) * 64), int(u * 64)]
    row = conductor_ior_row(gold)
    eta, k = np.array(row["eta"]), np.array(row["k"])
    np.testing.assert_allclose(pixel, ((eta - 1) ** 2 + k ** 2) / ((eta + 1) ** 2 + k ** 2), rtol=1e-5)
    assert pixel[0] > pixel[1] > pixel[2]  # gold


SKY_SCENE = sdf_scene(16, 'type = "sky"', BALL)


def test_an_environment_edit_is_the_edited_scenes_image_and_compiles_nothing(tmp_path):
    path = tmp_path / "sky.toml"
    path.write_text(SKY_SCENE)
    scene = load_scene(path)
    renderer = Renderer(scene)
    image(renderer, scene)
    compiled = kernels_compiled()
    brighter = replace(scene, environment=replace(scene.environment, intensity=2.5, rotation=30.0))
    assert renderer.edit_environment(brighter.environment)
    edited = image(renderer, brighter)
    assert kernels_compiled() == compiled and renderer.scene.environment == brighter.environment
    np.testing.assert_array_equal(edited, fresh(brighter))
    assert not renderer.edit_environment(replace(scene.environment, kind="constant"))
    assert renderer.scene.environment == brighter.environment

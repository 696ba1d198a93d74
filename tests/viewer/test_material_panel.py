"""The material panel with a stand-in for GGUI's imgui: the controls are the kind's fields of the
scene format, with the format's ranges in their labels; untouched controls change nothing; a
colour, a slider, a choice and the kind button edit the material; buttons are actions."""
from __future__ import annotations

from contextlib import contextmanager

from renderer.picking import Pick
from renderer.renderer import SurfaceHit
from renderer.scene.description import MaterialSpec
from viewer.material_panel import draw_material_panel, panel_fields

HIT = SurfaceHit(distance=4.0, point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0), uv=(0.0, 0.0), depth=4.0, material=0,
                 primitive=0, instance=-1, front_face=True)


class FakeGui:
    """Records the widgets drawn; answers with `values` (by label prefix) and `clicks`."""

    def __init__(self, values=None, clicks=()):
        self.values, self.clicks, self.drawn = dict(values or {}), set(clicks), []

    @contextmanager
    def sub_window(self, name, x, y, width, height):
        assert 0 <= x <= 1 and 0 <= y <= 1 and width > 0 and height > 0
        yield self

    def _answer(self, label, value):
        self.drawn.append(label)
        return next((v for k, v in self.values.items() if label.startswith(k)), value)

    def text(self, line, color=None):
        self.drawn.append(line)

    def button(self, label):
        self.drawn.append(label)
        return any(label.startswith(c) for c in self.clicks)

    slider_float = slider_int = lambda self, label, value, lo, hi: self._answer(label, value)
    color_edit_3 = checkbox = lambda self, label, value: self._answer(label, value)


def panel(spec, **gui):
    g = FakeGui(**gui)
    pick = Pick(HIT, 3, "objects[3] (quad)", 0, spec.name, spec.kind)
    edited, actions = draw_material_panel(g, (960, 540), pick, spec)
    return edited, actions, g.drawn


def test_untouched_controls_change_nothing_and_show_the_kinds_fields():
    spec = MaterialSpec("m", kind="principled", base_color=(0.2, 0.3, 0.4), roughness=0.35, metallic=0.5)
    edited, actions, drawn = panel(spec)
    assert edited is spec and actions == []
    assert "roughness [0, 1]" in drawn and "metallic [0, 1]" in drawn and "base_color" in drawn
    assert any(line.startswith("ior (1, 4]") for line in drawn)  # the range the format allows
    assert "edge_tint" not in drawn  # a conductor's
    names = {f.name for f in panel_fields(MaterialSpec("d"))}
    assert names >= {"base_color", "roughness", "emission", "opacity"} and "bump_scale" not in names
    assert "two_sided_emission" in {f.name for f in panel_fields(MaterialSpec("e", emission=(1.0, 1.0, 1.0)))}


def test_a_colour_a_slider_and_the_kind():
    spec = MaterialSpec("m", kind="diffuse", base_color=(0.8, 0.8, 0.8))
    edited, _, _ = panel(spec, values={"base_color": (1.0, 0.766, 0.336), "roughness": 0.25})
    assert edited.base_color == (1.0, 0.766, 0.336) and edited.roughness == 0.25 and edited.kind == "diffuse"
    edited, _, _ = panel(spec, clicks={"kind: diffuse"})
    assert edited.kind != "diffuse"
    silver, _, drawn = panel(MaterialSpec("g", kind="conductor"), values={"metal:": 2})
    assert silver.metal == "Ag" and "metal: (from the colour)" in drawn  # index 0: from base_color
    gold, _, _ = panel(spec, clicks={"make it gold"})
    assert (gold.kind, gold.metal) == ("conductor", "Au")
    _, _, drawn = panel(gold)
    assert "base_color" not in drawn and "edge_tint" not in drawn and "metal: Au" in drawn  # the metal's own Fresnel


def test_emission_is_a_colour_times_a_strength_and_buttons_are_actions():
    spec = MaterialSpec("light", emission=(10.0, 5.0, 0.0))
    edited, actions, drawn = panel(spec, values={"emission strength": 20.0}, clicks={"undo", "save scene"})
    assert edited.emission == (20.0, 10.0, 0.0) and actions == ["undo_edit", "save_scene"]
    assert "emission colour" in drawn


def test_the_environment_panel_turns_and_scales_it():
    from renderer.scene.description import EnvironmentSpec
    from viewer.material_panel import draw_environment_panel

    sky = EnvironmentSpec(kind="sky")
    g = FakeGui(values={"intensity": 2.0, "rotation": 45.0})
    edited, actions = draw_environment_panel(g, (960, 540), sky)
    assert (edited.intensity, edited.rotation, edited.kind) == (2.0, 45.0, "sky") and actions == []
    assert "zenith colour" in g.drawn and "intensity >= 0" in g.drawn
    same, _ = draw_environment_panel(FakeGui(), (960, 540), sky)
    assert same is sky


def test_the_light_panel_has_its_kinds_controls_and_the_environment_panel_lists_lights():
    import math

    from renderer.editing import SceneLight
    from renderer.scene.description import EnvironmentSpec, LightSpec
    from viewer.light_panel import angles_direction, direction_angles, draw_light_panel
    from viewer.material_panel import draw_environment_panel

    spot = SceneLight(2, LightSpec("spot", position=(0.0, 3.0, 0.0), direction=(0.0, -1.0, 0.0), intensity=(8.0, 4.0, 2.0)))
    g = FakeGui()
    same, actions = draw_light_panel(g, (960, 540), spot, extent=5.0)
    assert same is spot and actions == [] and "lights[2]: spot light" in g.drawn
    assert {"intensity colour", "position y", "elevation [-90, 90]", "beam_width [0, 20]"} <= set(g.drawn)
    assert any(label.startswith("cutoff_angle (0, 180)") for label in g.drawn)
    edited, _ = draw_light_panel(FakeGui(values={"intensity strength": 16.0, "position x": 1.0,
                                                 "elevation": -45.0}), (960, 540), spot, 5.0)
    assert edited.spec.intensity == (16.0, 8.0, 4.0) and edited.spec.position == (1.0, 3.0, 0.0)
    assert math.isclose(edited.spec.direction[1], -math.sqrt(0.5)) and edited.index == 2
    sun = SceneLight(0, LightSpec("directional", direction=(0.0, -1.0, 0.0)))
    g = FakeGui()
    draw_light_panel(g, (960, 540), sun, 5.0)
    assert "irradiance colour" in g.drawn and not any(label.startswith("position") for label in g.drawn)
    for d in [(0.3, -0.8, 0.52), (0.0, 1.0, 0.0), (-1.0, 0.0, 0.0)]:
        unit = tuple(c / math.hypot(*d) for c in d)
        assert all(math.isclose(a, b, abs_tol=1e-12) for a, b in zip(angles_direction(*direction_angles(d)), unit))
    g = FakeGui(clicks={"lights[1]"})
    _, actions = draw_environment_panel(g, (960, 540), EnvironmentSpec(kind="constant"),
                                        lights=(sun.spec, spot.spec))
    assert actions == ["open_light:1"] and "lights[0]: directional  (edit)" in g.drawn

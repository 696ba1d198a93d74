"""The material panel: the controls of the picked material's kind, drawn with GGUI's imgui, as
the scene format describes them (renderer/scene/schema.py, MATERIAL): a colour picker for each
colour, a slider for each number over the range the format allows (shown in its label), a box
for each switch, a button that steps through each choice. Textures are listed and kept.

draw_material_panel returns the edited material (the same object when nothing changed) and the
actions of the buttons clicked; the window applies them (viewer/scene_editor.py).
"""
from __future__ import annotations

from dataclasses import replace

from renderer.materials.metals import metal_names
from renderer.picking import Pick
from renderer.scene.description import MATERIAL_KINDS, EnvironmentSpec, MaterialSpec
from renderer.scene.schema import ENVIRONMENT, MATERIAL
from viewer.hud import ERROR_COLOR, MARGIN_PX, Rect, same_f32, slider_float, text_line

PANEL_WIDTH_PX = 440  # imgui gives labels a third of it: "roughness [0, 1]" must fit
PANEL_HEIGHT_PX = 640
# Slider ends for numbers whose range in the format is open (the format's own bound is kept by
# the editor's clamping; the slider only offers a useful span).
OPEN_RANGE_ENDS = {"abbe": 100.0, "coat_thickness": 1.0, "bump_scale": 4.0, "coat_maxdepth": 100,
                   "coat_nsamples": 16, "intensity": 10.0}
# The environment's fields per kind (its file and axis are kept; rotation turns about the axis)
ENVIRONMENT_FIELDS = {"map": ("intensity", "rotation"), "constant": ("intensity", "color"),
                      "sky": ("intensity", "rotation", "zenith", "horizon", "ground")}
EMISSION_STRENGTH_MAX = 100.0
# Fields the panel shows as text only: indices given per channel, and names of other tables.
NOT_SLIDERS = ("type", "eta", "k", "medium", "outside_medium", "glass", "normal_map", "bump_map", "roughness_v")
# One click to a metal (the kind becomes a conductor of that metal's measured index).
METAL_PRESETS = (("gold", "Au"), ("silver", "Ag"), ("copper", "Cu"), ("aluminium", "Al"))
ACTIONS = (("undo  [ctrl+z]", "undo_edit"), ("redo  [ctrl+y]", "redo_edit"), ("reset to the file's", "reset_material"),
           ("save scene  [ctrl+s]", "save_scene"), ("close", "close_panel"))


def notes_and_actions(g, notes) -> list[str]:
    """The end of every editing panel: what the last edit clamped (a line each, in the error
    colour), then the buttons of ACTIONS; returns the actions clicked."""
    for line in notes:
        text_line(g, line, ERROR_COLOR)
    return [action for label, action in ACTIONS if g.button(label)]


def panel_rect(window_size: tuple[int, int]) -> Rect:
    w, h = window_size
    width = min(PANEL_WIDTH_PX / w, 0.45)
    return Rect(1 - width - MARGIN_PX / w, MARGIN_PX / h, width, min(PANEL_HEIGHT_PX / h, 1 - 2 * MARGIN_PX / h))


# Fields that mean something only with another: shown where that one is set.
def _fresnel_from_colour(spec: MaterialSpec) -> bool:
    """A conductor's base_color and edge_tint shade it only where no metal or index is named."""
    return not (spec.kind == "conductor" and (spec.metal or spec.eta is not None))


NEEDS = {"bump_scale": lambda spec: spec.bump_map is not None,
         "two_sided_emission": lambda spec: max(spec.emission) > 0.0,
         "base_color": _fresnel_from_colour, "edge_tint": _fresnel_from_colour}


def panel_fields(spec: MaterialSpec) -> list:
    """The scene format's fields of a material's kind that the panel edits, in the format's order."""
    return [f for f in MATERIAL.fields if f.in_model and f.applies_to(spec.kind) and f.name not in NOT_SLIDERS
            and NEEDS.get(f.name, lambda _: True)(spec)]


def _step(options: tuple, value) -> object:
    return options[(options.index(value) + 1) % len(options)] if value in options else options[0]


def _span(f) -> tuple[float, float]:
    r = f.range
    if f.name == "rotation":
        return -180.0, 180.0
    lo = r.lo if r is not None and r.lo is not None else 0.0
    hi = r.hi if r is not None and r.hi is not None else OPEN_RANGE_ENDS.get(f.name, 10.0)
    return lo, hi


def _colour(g, label: str, value: tuple) -> tuple:
    new = tuple(float(c) for c in g.color_edit_3(label, tuple(value)))
    return tuple(value) if all(same_f32(a, b) for a, b in zip(new, value)) else new


def emission_control(g, value: tuple, name: str = "emission") -> tuple:
    """A radiance as a colour of largest channel 1 times a strength."""
    strength = max(value)
    colour = tuple(c / strength for c in value) if strength > 0 else (1.0, 1.0, 1.0)
    new_colour = _colour(g, f"{name} colour", colour)
    new_strength = slider_float(g, f"{name} strength [0, {EMISSION_STRENGTH_MAX:g}]", strength, 0.0,
                                EMISSION_STRENGTH_MAX)
    if new_colour == colour and new_strength == strength:
        return value
    return tuple(c * new_strength for c in new_colour)


def field_control(g, f, value):
    if f.name == "emission":
        return emission_control(g, value)
    if f.name == "metal":  # a slider over the named metals, 0: the Fresnel from base_color
        names = ("",) + tuple(metal_names())
        index = names.index(value) if value in names else 0
        chosen = int(g.slider_int(f"metal: {value or '(from the colour)'}", index, 0, len(names) - 1))
        return names[chosen] if 0 <= chosen < len(names) else value
    if f.choices:
        return _step(tuple(f.choices), value) if g.button(f"{f.name}: {value}") else value
    if f.kind == "vec3":
        return _colour(g, f.name, value)
    if f.kind == "bool":
        return bool(g.checkbox(f.name, bool(value)))
    lo, hi = _span(f)
    label = f"{f.name} {f.range}" if f.range is not None else f.name
    if f.kind == "int":
        return int(g.slider_int(label, int(value), int(lo), int(max(hi, value))))
    return slider_float(g, label, float(value), lo, hi)


def draw_material_panel(gui, window_size: tuple[int, int], picked: Pick, spec: MaterialSpec,
                        notes: list[str] = ()) -> tuple[MaterialSpec, list[str]]:
    """Draw the panel of the picked material (one of the scene's: a model file's own has
    viewer/model_material_panel.py); returns (the material as edited, actions)."""
    r = panel_rect(window_size)
    actions: list[str] = []
    with gui.sub_window("Material", r.x, r.y, r.width, r.height) as g:
        text_line(g, picked.object_label)
        text_line(g, picked.where())
        text_line(g, f"material '{spec.name}'")
        changes = {}
        for name, metal in METAL_PRESETS:
            if g.button(f"make it {name}"):
                changes.update(kind="conductor", metal=metal)
        kind = spec.kind
        if g.button(f"kind: {kind}  (next)"):
            kind = _step(tuple(MATERIAL_KINDS), kind)
        for f in panel_fields(spec):
            value = getattr(spec, f.model_attr)
            if value is None:
                continue
            new = field_control(g, f, value)
            if new != value and f.model_attr not in changes:
                changes[f.model_attr] = new
        for role in spec.textures:
            text_line(g, f"texture on {role} (kept)")
        actions += notes_and_actions(g, notes)
    if kind != spec.kind and "kind" not in changes:
        changes["kind"] = kind
    return (replace(spec, **changes) if changes else spec), actions


def draw_environment_panel(gui, window_size: tuple[int, int], spec: EnvironmentSpec,
                           notes: list[str] = (), lights: tuple = ()) -> tuple[EnvironmentSpec, list[str]]:
    """The environment's panel (a click on nothing opens it): its intensity, its turn about its
    axis and its colours, as the scene format has them, and a button per light without a surface
    (`lights`: the scene's), which no click can pick; returns (the environment as edited, actions)."""
    r = panel_rect(window_size)
    actions: list[str] = []
    changes = {}
    with gui.sub_window("Environment", r.x, r.y, r.width, r.height) as g:
        text_line(g, f"environment: {spec.kind}" + (f" {spec.file.name}" if spec.file is not None else ""))
        for f in ENVIRONMENT.fields:
            if f.name not in ENVIRONMENT_FIELDS.get(spec.kind, ()):
                continue
            value = getattr(spec, f.model_attr)
            if f.kind == "vec3" and f.range is not None and f.range.hi is None:  # radiance: any brightness
                new = emission_control(g, value, f.name)
            else:
                new = field_control(g, f, value)
            if new != value:
                changes[f.model_attr] = new
        for i, light in enumerate(lights):
            if g.button(f"lights[{i}]: {light.kind}  (edit)"):
                actions.append(f"open_light:{i}")
        actions += notes_and_actions(g, notes)
    if "rotation" in changes and spec.to_world is not None:
        changes["to_world"] = None  # a turn set here replaces a file's matrix about the same axis
    return (replace(spec, **changes) if changes else spec), actions

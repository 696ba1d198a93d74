"""The panel of a model file's own material (a glTF material, or OBJ's or PLY's read into glTF's
model): its factors as the scene format's [model_materials.<i>] names them (base colour, metallic,
roughness, emission, transmission, ior, clearcoat, specular), each a control over the range the
format allows; the textures are listed and kept (they multiply the factors).

draw_model_material_panel returns the material's edit (renderer/editing.py ModelMaterialEdit:
the factors that differ from the file's) or None where nothing changed, and the actions of the
buttons clicked; the window applies them (viewer/scene_editor.py).
"""
from __future__ import annotations

from dataclasses import replace
from typing import Optional

from renderer.editing import ModelMaterialEdit
from renderer.picking import Pick
from renderer.scene.model_material_edits import changes_between
from renderer.scene.schema import MODEL_MATERIAL
from viewer.hud import text_line
from viewer.material_panel import emission_control, field_control, notes_and_actions, panel_rect


def draw_model_material_panel(gui, window_size: tuple[int, int], picked: Pick, material,
                              notes: list[str] = ()) -> tuple[Optional[ModelMaterialEdit], list[str]]:
    """Draw the panel of `material` (the picked ModelMaterial as shown); returns (its edit, or
    None where untouched, and actions)."""
    pbr, file_pbr = material.pbr, material.file_pbr or material.pbr
    r = panel_rect(window_size)
    actions: list[str] = []
    changes = {}
    with gui.sub_window("Model material", r.x, r.y, r.width, r.height) as g:
        text_line(g, picked.object_label)
        text_line(g, picked.where())
        text_line(g, f"{picked.material_name}: '{pbr.name}' of the model file")
        for f in MODEL_MATERIAL.fields:
            value = getattr(pbr, f.model_attr)
            if f.name == "base_color":
                value = tuple(value[:3])
            new = emission_control(g, value) if f.name == "emission" else field_control(g, f, value)
            if new != value:
                changes[f.model_attr] = (*new, pbr.base_color_factor[3]) if f.name == "base_color" else new
        for slot in pbr.texture_slots:
            text_line(g, f"texture on {slot} (kept)")
        actions += notes_and_actions(g, notes)
    if not changes:
        return None, actions
    edited = replace(pbr, **changes)
    attributes = [f.model_attr for f in MODEL_MATERIAL.fields]
    return ModelMaterialEdit(picked.model_material, changes_between(file_pbr, edited, attributes)), actions

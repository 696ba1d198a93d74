"""Edits of model files' own materials (Scene.model_material_edits, the format's
[model_materials.<i>]): factors of the glTF material replaced, its textures kept."""
from __future__ import annotations

from dataclasses import replace

from renderer.scene.mesh_model import PbrMaterial


def edited_pbr(pbr: PbrMaterial, changes) -> PbrMaterial:
    """`pbr` with the factors `changes` ((attribute, value) pairs) sets; a base colour keeps the
    file's alpha."""
    values = dict(changes)
    if "base_color_factor" in values:
        values["base_color_factor"] = (*values["base_color_factor"][:3], pbr.base_color_factor[3])
    return replace(pbr, **values) if values else pbr


def changes_between(file_pbr: PbrMaterial, pbr: PbrMaterial, attributes) -> tuple:
    """The (attribute, value) pairs of `attributes` whose values differ: what an edit wrote (a base
    colour as RGB)."""
    changes = []
    for name in attributes:
        value = getattr(pbr, name)
        if value != getattr(file_pbr, name):
            changes.append((name, tuple(value[:3]) if name == "base_color_factor" else value))
    return tuple(sorted(changes))

"""The material-table side of Mitsuba's normalmap and bumpmap (numpy only): which model a scene
material's normal slot holds, and what the rows call for.

A row's normal slot (textures[2]) holds a glTF tangent-space normal map unless its
`normal_map_model` says otherwise (renderer/materials/kinds.py NORMAL_MAP_MODELS). Mitsuba's maps
perturb the frame the surface's texture parametrisation gives (dp/du, dp/dv), which the mesh
geometry computes per hit only where some row needs it (`needs_uv_partials`).
"""
from __future__ import annotations

import numpy as np

from renderer.materials.kinds import HEIGHT_MAP, KIND_IDS, NO_TEXTURE, SHADING_FRAME_MAP, TANGENT_SPACE_MAP


def normal_map_row(spec, texture_slots: dict) -> dict:
    """The normal-slot columns of a scene material (MaterialSpec) whose textures have the slots
    `texture_slots` by role: its model, and for a height map its scale."""
    if "normal" in texture_slots:
        return {"normal_map_model": SHADING_FRAME_MAP}
    if "bump" in texture_slots:
        return {"normal_map_model": HEIGHT_MAP, "normal_scale": float(spec.bump_scale)}
    return {"normal_map_model": TANGENT_SPACE_MAP}


def _mapped(textures, model) -> bool:
    return textures[2] != NO_TEXTURE and model != TANGENT_SPACE_MAP


def mapped_frame_uses(rows) -> dict:
    """The rows' share of MaterialRows.uses(): "mapped_frames" (a Mitsuba normal or height map)
    and "bump_maps" (a height map, whose texture gradient is then compiled in)."""
    return {"mapped_frames": any(_mapped(r["textures"], r["normal_map_model"]) for r in rows),
            "bump_maps": any(r["textures"][2] != NO_TEXTURE and r["normal_map_model"] == HEIGHT_MAP for r in rows)}


def oriented_rows(arrays: dict) -> np.ndarray:
    """Per row of the table's arrays (MaterialRows.arrays): whether its lobes are oriented along
    the surface's dp/du (anisotropic widths, or the Disney kind's `anisotropic`)."""
    disney = np.asarray(arrays["kind"]) == KIND_IDS["disney"]
    disney_oriented = (np.asarray(arrays["anisotropic"]) != 0.0) | (np.asarray(arrays["disney_textures"])[:, 1] != NO_TEXTURE)
    return ((np.asarray(arrays["roughness_v"]) >= 0.0) | (np.asarray(arrays["alpha_textures"])[:, 1] != NO_TEXTURE)
            | (disney & disney_oriented))


def needs_uv_partials(arrays: dict) -> bool:
    """Whether any row of the table's arrays (MaterialRows.arrays) shades in the frame of the
    surface's texture parametrisation, so hits must carry dp/du and dp/dv."""
    textures, models = arrays["textures"], arrays["normal_map_model"]
    return bool(np.any((textures[:, 2] != NO_TEXTURE) & (models != TANGENT_SPACE_MAP)) or np.any(oriented_rows(arrays)))

"""The scene format's [model_materials.<i>] tables: edits of a model file's own materials (glTF's,
and OBJ's or PLY's as they are mapped onto glTF's), which the scene does not define. A table sets
factors of the material as the model file gives it; its textures stay and multiply them. Kept
apart from schema.py, which lists it among its sections."""
from __future__ import annotations

from renderer.scene.schema_types import NON_NEGATIVE, UNIT, Field, Range, Section

MODEL_MATERIAL = Section(
    "model_materials.<i>",
    "Changes to the materials model files bring (glTF's own, and OBJ's or PLY's as read into glTF's "
    "model), which `[materials]` does not name: `<i>` is the material's number among them, 0-based, in "
    "the order the scene's objects read their files (the viewer's pick reports it: `model material 3`). "
    "Each field replaces the glTF factor it names; a texture on it stays and multiplies the new factor. "
    "Fields not written keep the file's. The viewer saves its edits of model materials this way.",
    (
        Field("base_color", "vec3", (1.0, 1.0, 1.0), "The base colour factor, linear RGB (its alpha stays "
              "the file's).", UNIT, attr="base_color_factor"),
        Field("metallic", "float", 1.0, "The metallic factor.", UNIT, attr="metallic_factor"),
        Field("roughness", "float", 1.0, "The roughness factor (perceptual).", UNIT, attr="roughness_factor"),
        Field("emission", "vec3", (0.0, 0.0, 0.0), "The emissive factor, linear RGB radiance (with "
              "KHR_materials_emissive_strength folded in).", NON_NEGATIVE, attr="emissive_factor"),
        Field("transmission", "float", 0.0, "The transmission factor (KHR_materials_transmission).", UNIT,
              attr="transmission_factor"),
        Field("ior", "float", 1.5, "The index of refraction (KHR_materials_ior).", Range(1.0, 4.0, lo_open=True)),
        Field("clearcoat", "float", 0.0, "The clearcoat factor (KHR_materials_clearcoat).", UNIT,
              attr="clearcoat_factor"),
        Field("clearcoat_roughness", "float", 0.0, "The clearcoat's roughness factor.", UNIT,
              attr="clearcoat_roughness_factor"),
        Field("specular", "float", 1.0, "The specular factor (KHR_materials_specular).", UNIT,
              attr="specular_factor"),
    ),
    heading="`[model_materials.<i>]`",
)

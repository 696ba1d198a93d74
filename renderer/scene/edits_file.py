"""A scene of edits: a TOML file that names a scene of another format (Mitsuba 3, pbrt-v4, a model
file) and changes some of its materials and its environment, the way a viewer's edits of that scene
are kept (renderer/scene/edit_saving.py writes it):

    [scene]
    edits = "cornell-box.xml"        # relative to this file; read as it is, every time

    [materials.tall_box]             # a material of the edited scene, by its name there
    type = "conductor"               # only the fields written change; the rest stay the file's
    metal = "Au"

    [environment]
    intensity = 2.0

    [lights.0]                       # the file's first point, spot, directional or projector light
    intensity = [50, 40, 30]

The edited file and its models are referenced, never copied, so the scene of edits renders what the
edited file does with those values changed, bit for bit as the viewer showed it. A table's fields
are those of the TOML format's [materials.<name>], [environment] and [[lights]]
(renderer/scene/schema.py), checked the same way; a light keeps its type and image. A model
file's own materials are edited by [model_materials.<i>], as in any TOML scene. A conductor's Fresnel written in the table replaces the file's own description
of it (a `metal` drops the file's eta and k).
"""
from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

from renderer.scene import schema
from renderer.scene.conductor_fresnel import FRESNEL_DESCRIPTIONS, canonical
from renderer.scene.description import EnvironmentSpec, MaterialSpec, Scene
from renderer.scene.errors import SceneError
from renderer.scene.foreign_formats import is_foreign, load_foreign
from renderer.scene.load_options import LoadOptions
from renderer.scene.references import missing_file_problem
from renderer.scene.toml_loader import (is_scene_of_edits, read_changes, read_model_material_edits, read_toml,
                                       scene_from_toml)

SECTIONS = ("scene", "materials", "environment", "lights", "model_materials")
HEADER_FIELDS = ("edits", "description")


def load_toml_scene(path, options: LoadOptions) -> Scene:
    """A TOML scene file: Lantern's own scene, or a scene of edits of another file."""
    data = read_toml(path, options)
    if not is_scene_of_edits(data):
        return scene_from_toml(data, path, options)
    return _edited_scene(data, Path(path), options)


def _edited_scene(data: dict, path: Path, options: LoadOptions) -> Scene:
    for key in data:
        if key not in SECTIONS:
            raise SceneError(path, f"section '{key}' is not part of a scene of edits (allowed: {', '.join(SECTIONS)}); "
                                   "the edited file gives the rest")
    header = data["scene"]
    for key in header:
        if key not in HEADER_FIELDS:
            raise SceneError(path, f"scene.{key}: not part of a scene of edits (allowed: {', '.join(HEADER_FIELDS)})")
    base = load_foreign(_edited_file(header["edits"], path), options)
    materials = data.get("materials", {})
    if not isinstance(materials, dict):
        raise SceneError(path, "materials: expected a table of materials by name")
    known = {m.name for m in base.materials}
    for name in materials:
        if name not in known:
            raise SceneError(path, f"materials.{name}: the edited scene has no material '{name}' "
                                   f"(its materials: {', '.join(sorted(known)) or 'none'})")
    edited = tuple(edited_material(m, materials[m.name], path, base.geometry) if m.name in materials else m
                   for m in base.materials)
    environment = base.environment
    if "environment" in data:
        environment = edited_environment(base.environment, data["environment"], path, base.geometry)
    lights = base.lights
    if "lights" in data:
        lights = edited_lights(base.lights, data["lights"], path, base.geometry)
    description = header.get("description", base.description)
    if not isinstance(description, str):
        raise SceneError(path, "scene.description: expected a string")
    model_edits = read_model_material_edits(data.get("model_materials"), path)
    return replace(base, path=path, materials=edited, environment=environment, lights=lights,
                   model_material_edits=model_edits or base.model_material_edits, description=description,
                   source_files=(*base.source_files, Path(base.path)), edited_from=base)


def _edited_file(raw: object, path: Path) -> Path:
    if not isinstance(raw, str) or not raw:
        raise SceneError(path, "scene.edits: expected the edited scene's file name (a string)")
    file = (path.parent / raw).resolve()
    if not is_foreign(file):
        raise SceneError(path, f"scene.edits: {raw} is not a Mitsuba (.xml), pbrt (.pbrt) or model file "
                               "(a TOML scene's edits are saved in a copy of it)")
    if not file.is_file():
        raise SceneError(path, f"scene.edits: {raw}: {missing_file_problem(file)}")
    return file


def _values(spec, section: schema.Section) -> dict:
    """A spec's values by the section's field names (what its rules read)."""
    values = {f.name: getattr(spec, f.model_attr) for f in section.fields if f.in_model and hasattr(spec, f.model_attr)}
    return {**{f.name: f.default for f in section.fields if f.name not in values}, **values}


def edited_material(base: MaterialSpec, table: object, path: Path, geometry: str) -> MaterialSpec:
    """`base` with the fields a scene of edits' [materials.<name>] table writes."""
    where = f"materials.{base.name}"
    kind, values = base.kind, _values(base, schema.MATERIAL)
    if isinstance(table, dict) and "type" in table:  # the type decides which fields the table may hold
        kind = read_changes({"type": table["type"]}, schema.MATERIAL, where, None, path, geometry, values)["type"]
    changes = read_changes(table, schema.MATERIAL, where, kind, path, geometry, values)
    strength = changes.pop("emission_strength", 1.0)
    emission = tuple(c * strength for c in changes.get("emission", base.emission))
    if not all(c <= schema.F32_MAX for c in emission):
        raise SceneError(path, f"{where}: emission * emission_strength is beyond the 32-bit float range")
    changes["emission"] = emission
    attrs = {schema.MATERIAL.field(name).model_attr: value for name, value in changes.items()}
    spec = replace(base, **{**attrs, "kind": kind})
    written = next((d for d in FRESNEL_DESCRIPTIONS if any(name in changes for name in d)), None)
    return canonical(spec, written) if written is not None else spec


def edited_environment(base: EnvironmentSpec, table: object, path: Path, geometry: str) -> EnvironmentSpec:
    """`base` with the values a scene of edits' [environment] table writes (its type and image
    stay the edited file's)."""
    if isinstance(table, dict):
        for key in ("type", "file"):
            if key in table:
                raise SceneError(path, f"environment.{key}: a scene of edits keeps the environment's {key} "
                                       "(edit the scene's own file to change it)")
    changes = read_changes(table, schema.ENVIRONMENT, "environment", base.kind, path, geometry,
                           _values(base, schema.ENVIRONMENT))
    return replace(base, **{schema.ENVIRONMENT.field(name).model_attr: value for name, value in changes.items()})


def edited_lights(base: tuple, table: object, path: Path, geometry: str) -> tuple:
    """`base` (the edited file's lights) with the values a scene of edits' [lights.<i>] tables
    write (i: the light's 0-based place in the file; its type and image stay the file's)."""
    if not isinstance(table, dict):
        raise SceneError(path, "lights: expected tables by the light's place, e.g. [lights.0]")
    lights = list(base)
    for key, body in table.items():
        if not key.isdigit() or int(key) >= len(base):
            raise SceneError(path, f"lights.{key}: the edited scene has {len(base)} lights (lights.0 to "
                                   f"lights.{len(base) - 1})" if base else f"lights.{key}: the edited scene has no lights")
        i = int(key)
        for fixed in ("type", "texture"):
            if isinstance(body, dict) and fixed in body:
                raise SceneError(path, f"lights.{key}.{fixed}: a scene of edits keeps the light's {fixed}")
        changes = read_changes(body, schema.LIGHT, f"lights.{key}", base[i].kind, path, geometry,
                               _values(base[i], schema.LIGHT))
        lights[i] = replace(base[i], **{schema.LIGHT.field(name).model_attr: value for name, value in changes.items()})
    return tuple(lights)


def relative_reference(file: Path, directory: Path) -> str:
    """How a scene of edits in `directory` names `file`."""
    return Path(os.path.relpath(file, directory)).as_posix()

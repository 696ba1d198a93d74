"""Edits written back to a TOML scene file: materials as the inverse of the loader's
[materials.<name>] tables (renderer/scene/toml_loader.py) and the environment's changed values,
put into the file the scene came from, whose other tables, comments and layout stay as they were.
The result goes beside the original (`<name>_edited.toml`) unless the caller asks to write over it.

A scene of another format (Mitsuba, pbrt, a model file) is saved as a TOML scene of edits
(renderer/scene/edits_file.py): the file it came from, referenced, and the values that differ from
it. Before a file is written, what it says is read back in memory and compared with the edited
scene; a value the format cannot carry is an error, never a file that renders otherwise.

A material table holds the fields of the scene format (renderer/scene/schema.py, MATERIAL) that
apply to the material's kind and differ from their defaults; roughness is always written (its
default depends on the kind). What the format cannot say (a texture on a colour, a mix) is one
SceneError naming the material and the field, never a file that renders otherwise.
"""
from __future__ import annotations

import math
from dataclasses import fields
from pathlib import Path
from typing import Optional

import tomlkit

from renderer.scene.conductor_fresnel import canonical, description_of, other_fields
from renderer.scene.description import EnvironmentSpec, LightSpec, MaterialSpec, Scene, TextureSpec
from renderer.scene.edits_file import edited_environment, edited_lights, edited_material, relative_reference
from renderer.scene.errors import SceneError
from renderer.scene.foreign_formats import is_foreign
from renderer.scene.schema import ENVIRONMENT, LIGHT, MATERIAL, MODEL_MATERIAL

EDITED_SUFFIX = "_edited"


def edited_path(original: Path) -> Path:
    """Where an edited scene is saved by default: beside the original, `<stem>_edited.toml`."""
    stem = original.name
    for suffix in (".gz", ".pbrt", original.suffix):
        stem = stem[: -len(suffix)] if suffix and stem.lower().endswith(suffix) else stem
    stem = stem[: -len(EDITED_SUFFIX)] if stem.endswith(EDITED_SUFFIX) else stem
    return original.with_name(f"{stem}{EDITED_SUFFIX}.toml")


def material_table(spec: MaterialSpec, directory: Path) -> dict:
    """The [materials.<name>] table of `spec`, its file paths relative to `directory`."""
    spec = canonical(spec)  # the format's one Fresnel description of a conductor
    table: dict = {}
    covered = {"name"}
    for f in MATERIAL.fields:
        covered.add(f.model_attr)
        if not f.in_model or not f.applies_to(spec.kind):
            continue
        value = spec.kind if f.name == "type" else getattr(spec, f.model_attr)
        if f.name in ("normal_map", "bump_map"):
            if value is not None:
                table[f.name] = relative_reference(value.file, directory)
            continue
        if value is None or (f.name not in ("type", "roughness") and value == f.default_for(spec.kind)):
            continue
        table[f.name] = list(value) if isinstance(value, tuple) else value
    default = MaterialSpec(spec.name, spec.kind)
    for f in fields(MaterialSpec):
        if f.name not in covered and getattr(spec, f.name) != getattr(default, f.name):
            raise SceneError(directory, f"material '{spec.name}': its {f.name} cannot be written in a TOML scene")
    return table


def save_edits(scene: Scene, loaded: Scene, path: Optional[Path] = None, overwrite: bool = False) -> Path:
    """Write `scene`, the scene `loaded` with materials, the environment, lights or model
    materials edited, to `path` (default: edited_path of the original). A TOML original: its text
    with each changed material's table replaced and the other changed values set. Any other
    format (or a scene of edits): a scene of edits of that file (edits_document). Writing over the
    original needs `overwrite`. Returns the path written."""
    original = Path(loaded.path)
    target = Path(path) if path is not None else edited_path(original)
    if target.resolve() == original.resolve() and not overwrite:
        raise SceneError(target, "is the scene's own file: saving over it must be asked for")
    base = loaded.edited_from or (loaded if is_foreign(original) else None)
    if base is not None:
        return _write(target, edits_document(scene, base, target))
    if target.parent.resolve() != original.parent.resolve():
        raise SceneError(target, "an edited scene is saved in its original's folder, where its files resolve")
    document = tomlkit.parse(original.read_text(encoding="utf-8"))
    was = {m.name: m for m in loaded.materials}
    if "materials" not in document:
        document["materials"] = tomlkit.table(is_super_table=True)
    for spec in scene.materials:
        if was.get(spec.name) != spec:
            document["materials"][spec.name] = _toml_table(material_table(spec, target.parent))
    if scene.environment != loaded.environment:
        _environment_into(document, scene.environment, loaded.environment, target)
    for i, (spec, was_light) in enumerate(zip(scene.lights, loaded.lights)):
        if spec != was_light:  # the changed values set in the light's own [[lights]] table
            for key, value in _light_changes(spec, was_light, target).items():
                document["lights"][i][key] = value
    if scene.model_material_edits != loaded.model_material_edits:
        if "model_materials" in document:
            del document["model_materials"]
        if scene.model_material_edits:
            document.add("model_materials", model_materials_table(scene.model_material_edits))
    return _write(target, tomlkit.dumps(document))


def model_materials_table(edits: tuple):
    """[model_materials.<i>] tables of Scene.model_material_edits."""
    names = {f.model_attr: f.name for f in MODEL_MATERIAL.fields}
    table = tomlkit.table(is_super_table=True)
    for index, changes in edits:
        table.add(str(index), _toml_table({names[attr]: list(value) if isinstance(value, tuple) else value
                                           for attr, value in changes}))
    return table


def _write(target: Path, text: str) -> Path:
    try:
        target.write_text(text, encoding="utf-8")
    except OSError as error:
        raise SceneError(target, f"cannot be written ({error.strerror or error})") from None
    return target


def edits_document(scene: Scene, base: Scene, target: Path) -> str:
    """The TOML scene of edits, saved as `target`, that turns `base` (a scene of another format, as
    its file gives it) into `scene`."""
    others = _other_changes(scene, base)
    if others:
        raise SceneError(base.path, f"a scene of edits holds materials, the environment and lights; its {others} "
                                    "changed too")
    document = tomlkit.document()
    document.add(tomlkit.comment(f"Edits of {Path(base.path).name}: the values below replace that file's; "
                                 "everything else is read from it."))
    header = tomlkit.table()
    header.add("edits", relative_reference(Path(base.path), target.parent))
    if scene.description != base.description:
        header.add("description", scene.description)
    document.add("scene", header)
    materials = tomlkit.table(is_super_table=True)
    for was, spec in zip(base.materials, scene.materials):
        if was.name != spec.name:
            raise SceneError(base.path, "the edited scene's materials are not the file's (a scene of edits keeps them)")
        if was != spec:
            materials.add(spec.name, _changes_table(spec, was, target, scene.geometry))
    if len(materials):
        document.add("materials", materials)
    if scene.environment != base.environment:
        document.add("environment", _environment_changes(scene.environment, base.environment, target, scene.geometry))
    lights = tomlkit.table(is_super_table=True)
    for i, (spec, was) in enumerate(zip(scene.lights, base.lights)):
        if spec != was:
            values = _light_changes(spec, was, target)
            _check_read_back(edited_lights((was,), {"0": values}, target, scene.geometry)[0], spec,
                             f"lights[{i}]", target)
            lights.add(str(i), _toml_table(values))
    if len(lights):
        document.add("lights", lights)
    if scene.model_material_edits:
        document.add("model_materials", model_materials_table(scene.model_material_edits))
    return tomlkit.dumps(document)


def _other_changes(scene: Scene, base: Scene) -> str:
    kept = {"path", "materials", "environment", "lights", "model_material_edits", "description", "source_files",
            "edited_from"}
    return ", ".join(f.name for f in fields(Scene) if f.compare and f.name not in kept
                     and getattr(scene, f.name) != getattr(base, f.name))


def _changed_fields(spec, was, section, kind: str, directory: Path) -> dict:
    """The section's fields whose values differ between `was` and `spec`, as TOML values."""
    table = {}
    for f in section.fields:
        if not f.in_model or f.name == "type" or not f.applies_to(kind) or not hasattr(spec, f.model_attr):
            continue
        value = getattr(spec, f.model_attr)
        if value == getattr(was, f.model_attr) or value is None:
            continue  # None: dropped with another description written (edits_file.py)
        if isinstance(value, TextureSpec):
            if f.name not in ("normal_map", "bump_map"):
                continue  # the read-back comparison names it
            value = relative_reference(value.file, directory)
        table[f.name] = list(value) if isinstance(value, tuple) else value
    return table


def _changes_table(spec: MaterialSpec, was: MaterialSpec, target: Path, geometry: str):
    spec = canonical(spec)
    values = ({"type": spec.kind} if spec.kind != was.kind else {}) | _changed_fields(spec, was, MATERIAL, spec.kind, target.parent)
    if spec.kind == "conductor":  # the one Fresnel description written drops the file's others
        implied = other_fields(description_of(spec))
        values = {key: value for key, value in values.items() if key not in implied}
    _check_read_back(edited_material(was, values, target, geometry), spec, f"material '{spec.name}'", target)
    return _toml_table(values)


def _environment_values(spec: EnvironmentSpec, was: EnvironmentSpec, target: Path) -> dict:
    if (spec.kind, spec.file) != (was.kind, was.file):
        raise SceneError(target, "an edit of the environment keeps its kind and image")
    return _changed_fields(spec, was, ENVIRONMENT, spec.kind, target.parent)


def _environment_changes(spec: EnvironmentSpec, was: EnvironmentSpec, target: Path, geometry: str):
    values = _environment_values(spec, was, target)
    _check_read_back(edited_environment(was, values, target, geometry), spec, "the environment", target)
    return _toml_table(values)


def _light_changes(spec: LightSpec, was: LightSpec, target: Path) -> dict:
    if (spec.kind, spec.texture) != (was.kind, was.texture):
        raise SceneError(target, "an edit of a light keeps its type and image")
    return _changed_fields(spec, was, LIGHT, spec.kind, target.parent)


def _check_read_back(read, spec, what: str, target: Path) -> None:
    # A direction is normalised on reading: one normalisation more may move its last bit (its
    # float32 copy on the device stays the same)
    differ = [f.name for f in fields(spec) if getattr(read, f.name) != getattr(spec, f.name)
              and not (f.name == "direction" and math.dist(read.direction, spec.direction) < 1e-12)]
    if differ:
        raise SceneError(target, f"{what}: its {', '.join(differ)} cannot be written in a scene of edits")


def _toml_table(values: dict):
    table = tomlkit.table()
    for key, value in values.items():
        table.add(key, value)
    return table


def _environment_into(document, spec, was, target: Path) -> None:
    """The environment's values that changed, set in the TOML document's [environment]."""
    if "environment" not in document:
        document["environment"] = tomlkit.table()
        document["environment"]["type"] = spec.kind
    for key, value in _environment_values(spec, was, target).items():
        document["environment"][key] = value

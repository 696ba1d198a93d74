"""Edits written back to a TOML scene file: materials as the inverse of the loader's
[materials.<name>] tables (renderer/scene/toml_loader.py) and the environment's changed values,
put into the file the scene came from, whose other tables, comments and layout stay as they were.
The result goes beside the original (`<name>_edited.toml`) unless the caller asks to write over it.

A material table holds the fields of the scene format (renderer/scene/schema.py, MATERIAL) that
apply to the material's kind and differ from their defaults; roughness is always written (its
default depends on the kind). What the format cannot say (a texture on a colour, a mix) is one
SceneError naming the material and the field, never a file that renders otherwise.
"""
from __future__ import annotations

import os
from dataclasses import fields
from pathlib import Path
from typing import Optional

import tomlkit

from renderer.editing import canonical
from renderer.scene.description import MaterialSpec, Scene
from renderer.scene.errors import SceneError
from renderer.scene.schema import ENVIRONMENT, MATERIAL

EDITED_SUFFIX = "_edited"


def edited_path(original: Path) -> Path:
    """Where an edited scene is saved by default: beside the original, `<stem>_edited.toml`."""
    stem = original.stem if not original.stem.endswith(EDITED_SUFFIX) else original.stem[: -len(EDITED_SUFFIX)]
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
                table[f.name] = _relative(value.file, directory)
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
    """Write `scene`, the TOML scene `loaded` with materials or the environment edited, to `path`
    (default: edited_path of the original): the original file's text with each changed material's
    table replaced and the environment's changed values set. Writing over the original needs
    `overwrite`. Returns the path written."""
    original = Path(loaded.path)
    if original.suffix.lower() != ".toml":
        raise SceneError(original, "only scenes read from TOML files are saved with their edits so far")
    target = Path(path) if path is not None else edited_path(original)
    if target.resolve() == original.resolve() and not overwrite:
        raise SceneError(target, "is the scene's own file: saving over it must be asked for")
    if target.parent.resolve() != original.parent.resolve():
        raise SceneError(target, "an edited scene is saved in its original's folder, where its files resolve")
    document = tomlkit.parse(original.read_text(encoding="utf-8"))
    was = {m.name: m for m in loaded.materials}
    if "materials" not in document:
        document["materials"] = tomlkit.table(is_super_table=True)
    for spec in scene.materials:
        if was.get(spec.name) == spec:
            continue
        table = tomlkit.table()
        for key, value in material_table(spec, target.parent).items():
            table.add(key, value)
        document["materials"][spec.name] = table
    if scene.environment != loaded.environment:
        _environment_into(document, scene.environment, loaded.environment, original)
    try:
        target.write_text(tomlkit.dumps(document), encoding="utf-8")
    except OSError as error:
        raise SceneError(target, f"cannot be written ({error.strerror or error})") from None
    return target


def _environment_into(document, spec, was, original: Path) -> None:
    """The environment's values that changed (its kind and image stay: edits keep them)."""
    if (spec.kind, spec.file) != (was.kind, was.file):
        raise SceneError(original, "an edit of the environment keeps its kind and image")
    if "environment" not in document:
        document["environment"] = tomlkit.table()
        document["environment"]["type"] = spec.kind
    table = document["environment"]
    for f in ENVIRONMENT.fields:
        if not f.in_model or f.name in ("type", "file") or not hasattr(spec, f.model_attr):
            continue
        value = getattr(spec, f.model_attr)
        if value != getattr(was, f.model_attr):
            table[f.name] = list(value) if isinstance(value, tuple) else value


def _relative(file: Path, directory: Path) -> str:
    return Path(os.path.relpath(file, directory)).as_posix()

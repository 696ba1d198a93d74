"""Load a TOML scene file into the plain-data model, validating it against schema.py.

Every problem becomes a one-line SceneError "<file>: <where>: <problem>", where <where> names
the section, field or object (e.g. "objects[1].children[0].radius").
"""
from __future__ import annotations

import dataclasses
import math
import os
import tomllib
from pathlib import Path, PurePath
from typing import Optional

from . import schema
from .errors import SceneError
from .load_options import LoadOptions
from .description import (
    MESH_OBJECT_KINDS,
    CameraSpec,
    EnvironmentSpec,
    MarchSettings,
    FogSpec,
    LightSpec,
    MaterialSpec,
    MediumSpec,
    MeshObject,
    RenderSettings,
    Scene,
    SdfNode,
    TextureSpec,
    Transform,
)
from .grid_media import VOL_EXTENSIONS, GridFieldError, grid_volumes
from .model_files import ModelFiles
from .references import missing_file_problem
from .schema_types import WRITTEN, Field, Generator, MeshKind, NodeKind, Section, format_number

# Python objects of a parsed TOML file per byte of its text (a file of empty inline tables comes
# to ~60; tests/scene/test_input_limits.py measures it): checked against the memory budget first.
TOML_PARSE_BYTES_PER_BYTE = 100


class _Invalid(Exception):
    """A validation problem at a place in the file; load_scene adds the file path."""

    def __init__(self, where: str, message: str):
        super().__init__(where, message)
        self.where = where
        self.message = message

    def text(self) -> str:
        return f"{self.where}: {self.message}" if self.where else self.message


def load_scene(path: str | os.PathLike, options: Optional[LoadOptions] = None) -> Scene:
    """Read and validate a scene file. Raises SceneError (one line) on any problem.
    `options`: the memory budget and rules its model files are read under (default LoadOptions())."""
    options = options or LoadOptions()
    return scene_from_toml(read_toml(path, options), path, options)


def scene_from_toml(data: dict, path: str | os.PathLike, options: LoadOptions) -> Scene:
    """The scene of a parsed TOML scene file (not a scene of edits: renderer/scene/edits_file.py)."""
    try:
        if is_scene_of_edits(data):
            raise _Invalid("scene.edits", "a scene of edits is opened with renderer.scene.catalog.load_any")
        return _build_scene(data, Path(path), ModelFiles(options))
    except _Invalid as problem:
        raise SceneError(path, problem.text()) from None


def read_model_material_edits(raw: object, scene_path: Path) -> tuple:
    """A file's [model_materials.<i>] tables as Scene.model_material_edits. Raises SceneError."""
    try:
        return _read_model_materials(raw)
    except _Invalid as problem:
        raise SceneError(scene_path, problem.text()) from None


def _read_model_materials(raw: object) -> tuple:
    """(i, ((PbrMaterial attribute, value), ...)) per [model_materials.<i>] table, by i."""
    edits = []
    by_name = {f.name: f for f in schema.MODEL_MATERIAL.fields}
    for key, body in ({} if raw is None else _table(raw, "model_materials")).items():
        where = f"model_materials.{key}"
        if not key.isdigit():
            raise _Invalid(where, "expected a model material's number (0-based), e.g. [model_materials.0]")
        body = _table(body, where)
        _check_keys(body, schema.MODEL_MATERIAL.fields, where, None)
        edits.append((int(key), tuple(sorted((by_name[k].model_attr, _convert(by_name[k], v, f"{where}.{k}"))
                                             for k, v in body.items()))))
    return tuple(sorted(edits))


def is_scene_of_edits(data: dict) -> bool:
    """Whether a parsed TOML scene file changes a scene of another format ([scene] edits = FILE)."""
    return isinstance(data.get("scene"), dict) and "edits" in data["scene"]


def read_changes(table: object, section: Section, where: str, kind: Optional[str], scene_path: Path,
                 geometry: str, base: dict) -> dict:
    """The fields a table of a scene of edits writes, converted and checked as in a full table, by
    field name; `base`: the edited values by field name, which the section's rules see beneath the
    written ones (a conductor's Fresnel is then still described once). Raises SceneError."""
    try:
        table = _table(table, where)
        _check_keys(table, section.fields, where, kind)
        _check_geometry(table, section, where, geometry)
        by_name = {f.name: f for f in section.fields if f.applies_to(kind)}
        changes = {}
        for key, raw in table.items():
            if key in ("normal_map", "bump_map"):
                changes[key] = _map_image(_string(raw, f"{where}.{key}"), scene_path, f"{where}.{key}")
            else:
                changes[key] = _convert(by_name[key], raw, f"{where}.{key}")
        _apply_rules(section.rules, {**base, **changes, "type": kind, WRITTEN: frozenset(table)}, where)
        return changes
    except _Invalid as problem:
        raise SceneError(scene_path, problem.text()) from None


# --- the file itself -------------------------------------------------------------------------


def _extension_text(suffix: str) -> str:
    return f"extension '{suffix}'" if suffix else "file without an extension"


def read_toml(path: str | os.PathLike, options: LoadOptions) -> dict:
    """The parsed TOML of a scene file, its size checked against the memory budget first."""
    file = Path(path)
    if not file.exists():
        raise SceneError(path, missing_file_problem(file))
    if file.is_dir():
        raise SceneError(path, "is a directory, not a scene file")
    if file.suffix.lower() not in schema.SCENE_EXTENSIONS:
        raise SceneError(path, f"unsupported scene {_extension_text(file.suffix)} (expected .toml)")
    try:
        size = file.stat().st_size
        options.budget.check(path, f"parsing this {size}-byte scene file", size * TOML_PARSE_BYTES_PER_BYTE)
        raw = file.read_bytes()
    except OSError as err:
        raise SceneError(path, f"cannot read file: {err.strerror or err}") from None
    try:
        text = raw.decode("utf-8-sig")  # tolerate the byte-order mark some editors write
    except UnicodeDecodeError as err:
        raise SceneError(path, f"not UTF-8 text (bad byte at offset {err.start})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SceneError(path, f"invalid TOML: {err}") from None
    except RecursionError:  # the parser recurses once per level of inline tables and arrays
        raise SceneError(path, "invalid TOML: arrays or inline tables nested too deeply to read") from None


# --- raw values ------------------------------------------------------------------------------


def _describe(raw: object) -> str:
    """A raw TOML value as the user would recognise it, for 'expected X, got Y' messages."""
    if isinstance(raw, bool):
        return f"boolean {'true' if raw else 'false'}"
    if isinstance(raw, int):
        return f"integer {raw}"
    if isinstance(raw, float):
        return f"float {raw!r}"
    if isinstance(raw, str):
        return f"string {raw[:40]!r}"
    if isinstance(raw, list):
        return "array"
    if isinstance(raw, dict):
        return "table"
    return f"date/time {raw}"


def _toml_list(raw: list) -> str:
    return "[" + ", ".join(str(x) if isinstance(x, int) else repr(x) for x in raw) + "]"


def _number(raw: object, where: str) -> float:
    # bool is a subclass of int in Python, but `true` is never a number in a scene file.
    if isinstance(raw, bool) or not isinstance(raw, (int, float)):
        raise _Invalid(where, f"expected a number, got {_describe(raw)}")
    value = float(raw)
    if not math.isfinite(value):
        raise _Invalid(where, f"{raw!r} is not a finite number")
    _check_f32(value, where)
    return value


def _check_f32(value: float, where: str) -> None:
    if abs(value) > schema.F32_MAX:
        raise _Invalid(where, f"{format_number(value)} is beyond the 32-bit float range "
                              f"(magnitudes up to {schema.F32_MAX:.4g})")


def _integer(raw: object, where: str) -> int:
    if isinstance(raw, bool) or not isinstance(raw, int):
        raise _Invalid(where, f"expected an integer, got {_describe(raw)}")
    return raw


def _boolean(raw: object, where: str) -> bool:
    if not isinstance(raw, bool):
        raise _Invalid(where, f"expected true or false, got {_describe(raw)}")
    return raw


def _string(raw: object, where: str) -> str:
    if not isinstance(raw, str):
        raise _Invalid(where, f"expected a string, got {_describe(raw)}")
    return raw


def _table(raw: object, where: str) -> dict:
    if not isinstance(raw, dict):
        raise _Invalid(where, f"expected a table, got {_describe(raw)}")
    return raw


def _tables(raw: object, where: str) -> list[dict]:
    if not isinstance(raw, list):
        raise _Invalid(where, f"expected an array of tables, got {_describe(raw)}")
    for i, item in enumerate(raw):
        _table(item, f"{where}[{i}]")
    return raw


def _vector(raw: object, where: str, item, n: int) -> tuple:
    if not isinstance(raw, list):
        raise _Invalid(where, f"expected an array of {n} numbers, got {_describe(raw)}")
    if len(raw) != n:
        raise _Invalid(where, f"expected {n} numbers, got {len(raw)}")
    return tuple(item(x, f"{where}[{i}]") for i, x in enumerate(raw))


def _triple(raw: object, where: str, item) -> tuple:
    return _vector(raw, where, item, 3)


def _direction(raw: object, where: str) -> tuple[float, float, float]:
    v = _triple(raw, where, _number)
    length = math.hypot(*v)  # hypot avoids underflow on tiny but non-zero vectors
    if length == 0.0:
        raise _Invalid(where, "must not be the zero vector")
    return tuple(c / length for c in v)


def _pairs(raw: object, where: str) -> tuple:
    """An array of [x, y] arrays (a Bezier profile), each checked where it stands."""
    if not isinstance(raw, list):
        raise _Invalid(where, f"expected an array of [number, number] pairs, got {_describe(raw)}")
    return tuple(_vector(item, f"{where}[{i}]", _number, 2) for i, item in enumerate(raw))


def _scale(raw: object, where: str) -> float:
    if not isinstance(raw, list):
        return _number(raw, where)
    v = _triple(raw, where, _number)
    if not v[0] == v[1] == v[2]:
        raise _Invalid(where, f"non-uniform scale {_toml_list(raw)} breaks the SDF distance bound; "
                              "use a uniform scale")
    return v[0]


def _scale3(raw: object, where: str):
    """A number or 3 numbers, kept as written so that range errors name the right place;
    `_expand_scale` makes the 3-vector."""
    return _triple(raw, where, _number) if isinstance(raw, list) else _number(raw, where)


_CONVERTERS = {
    "bool": _boolean,
    "string": _string,
    "int": _integer,
    "float": _number,
    "vec3": lambda raw, where: _triple(raw, where, _number),
    "vec2": lambda raw, where: _vector(raw, where, _number, 2),
    "points2": _pairs,
    "dir3": _direction,
    "int3": lambda raw, where: _triple(raw, where, _integer),
    "int4": lambda raw, where: _vector(raw, where, _integer, 4),
    "scale": _scale,
    "scale3": _scale3,
    "table": _table,
    "tables": _tables,
}


def _check_range(field: Field, value, where: str) -> None:
    if field.range is None:
        return
    components = value if isinstance(value, tuple) else (value,)
    for i, c in enumerate(components):
        if c not in field.range:
            place = f"{where}[{i}]" if isinstance(value, tuple) else where
            raise _Invalid(place, f"{format_number(c)} is out of range (allowed: {field.range})")


def _convert(field: Field, raw: object, where: str):
    value = _CONVERTERS[field.kind](raw, where)
    if field.items is not None:
        # An array of tables with known fields (e.g. a water generator's waves): each table is read
        # like a section and kept as sorted (name, value) pairs, so the model stays hashable.
        return tuple(tuple(sorted(_read_fields(_table(item, f"{where}[{i}]"), field.items,
                                               f"{where}[{i}]").items()))
                     for i, item in enumerate(value))
    if field.choices is not None and value not in field.choices:
        raise _Invalid(where, f"unknown value '{value}' (allowed: {', '.join(field.choices)})")
    _check_range(field, value, where)
    return value


# --- tables ----------------------------------------------------------------------------------


def _check_keys(table: dict, fields: tuple[Field, ...], where: str, kind: Optional[str],
                selector: str = "type") -> None:
    # Several kinds may have a field of the same name (e.g. generators' `size`): the one that
    # applies to `kind` is the field.
    by_name = {}
    for f in fields:
        if f.name not in by_name or (f.applies_to(kind) and not by_name[f.name].applies_to(kind)):
            by_name[f.name] = f
    for key in table:
        field = by_name.get(key)
        if field is None:
            allowed = ", ".join(dict.fromkeys(f.name for f in fields if f.applies_to(kind)))
            raise _Invalid(where, f"unknown field '{key}' (allowed: {allowed})")
        if not field.applies_to(kind):
            owners = " or ".join(f"'{k}'" for f in fields if f.name == key for k in f.only_for)
            raise _Invalid(f"{where}.{key}", f"only allowed with {selector} {owners}, not '{kind}'")


def _check_geometry(table: dict, section: Section, where: str, geometry: str) -> None:
    """Fields that belong to other geometry kinds (e.g. [render.march] in a mesh scene)."""
    for field in section.fields:
        if field.name in table and not field.in_geometry(geometry):
            owners = " or ".join(f"'{g}'" for g in field.geometries)
            raise _Invalid(f"{where}.{field.name}",
                           f"only allowed in scenes with geometry {owners}, not '{geometry}'")


def _read_fields(table: dict, fields: tuple[Field, ...], where: str,
                 kind: Optional[str] = None, selector: str = "type") -> dict:
    """Check the keys, convert the values present and fill in defaults for the rest."""
    _check_keys(table, fields, where, kind, selector)
    values = {}
    for field in fields:
        if not field.applies_to(kind):
            # not this kind's field (_check_keys refused it in the table); its default stands
            # unless a field of the same name belongs to this kind
            values.setdefault(field.name, None if field.required else field.default_for(kind))
            continue
        if field.name in table:
            values[field.name] = _convert(field, table[field.name], f"{where}.{field.name}")
        elif field.required and field.applies_to(kind):
            raise _Invalid(where, f"missing required field '{field.name}'")
        else:
            values[field.name] = None if field.required else field.default_for(kind)
    return values


def _read_section(raw: object, section: Section, where: str) -> dict:
    """Read a table of `section`; a section with a `type` field has per-type fields."""
    table = {} if raw is None else _table(raw, where)
    kind = None
    if "type" in section.allowed():
        # The type decides which other fields belong here, so it is read first.
        type_field = section.field("type")
        kind = type_field.default
        if "type" in table:
            kind = _convert(type_field, table["type"], f"{where}.type")
    values = _read_fields(table, section.fields, where, kind)
    _apply_rules(section.rules, {**values, WRITTEN: frozenset(table)}, where)
    return values


def _apply_rules(rules, values: dict, where: str) -> None:
    for rule in rules:
        problem = rule.check(values)
        if problem:
            raise _Invalid(where, problem)


def _model_kwargs(section: Section, values: dict) -> dict:
    return {f.model_attr: values[f.name] for f in section.fields if f.in_model}


# --- sections --------------------------------------------------------------------------------


def _check_top_level(data: dict) -> None:
    for key in data:
        if key not in schema.TOP_LEVEL:
            raise _Invalid("", f"unknown section '{key}' (allowed: {', '.join(schema.TOP_LEVEL)})")
    if "scene" not in data:
        raise _Invalid("", "missing [scene] section (it must set 'geometry')")


def _read_render(raw: object, geometry: str) -> RenderSettings:
    values = _read_section(raw, schema.RENDER, "render")
    _check_geometry(raw or {}, schema.RENDER, "render", geometry)
    march = _read_section(values["march"], schema.MARCH, "render.march")
    return RenderSettings(**_model_kwargs(schema.RENDER, values),
                          march=MarchSettings(**_model_kwargs(schema.MARCH, march)))


def _or_list(items) -> str:
    items = list(items)
    return ", ".join(items[:-1]) + " or " + items[-1] if len(items) > 1 else "".join(items)


def _resolve_file(file: str, scene_path: Path, where: str, what: str,
                  extensions: tuple[str, ...]) -> Path:
    """A file named in the scene, relative to the scene's folder: checked, not read."""
    suffix = PurePath(file).suffix
    if suffix.lower() not in extensions:
        raise _Invalid(f"{where}.file", f"unsupported {what} {_extension_text(suffix)} "
                                        f"(expected {_or_list(extensions)})")
    noun = what.split()[-1]  # "environment map" -> "map", "model" -> "model"
    try:
        resolved = (scene_path.parent / file).resolve()
    except RuntimeError:  # Python's report of a symlink loop
        raise _Invalid(where, f"{noun} file {file} is a symlink loop") from None
    if not resolved.exists():
        raise _Invalid(where, f"missing {noun} file {file} (looked for {resolved})")
    if not resolved.is_file():
        raise _Invalid(where, f"{noun} file {file} is not a file")
    return resolved


def _read_environment(raw: object, scene_path: Path) -> EnvironmentSpec:
    values = _read_section(raw, schema.ENVIRONMENT, "environment")
    if values["type"] == "map":
        values["file"] = _resolve_file(values["file"], scene_path, "environment",
                                       "environment map", schema.ENV_MAP_EXTENSIONS)
    return EnvironmentSpec(**_model_kwargs(schema.ENVIRONMENT, values))


def _read_material(name: str, raw: object, scene_path: Path, geometry: str) -> MaterialSpec:
    where = f"materials.{name}"
    values = _read_section(raw, schema.MATERIAL, where)
    _check_geometry(raw, schema.MATERIAL, where, geometry)
    for field in ("normal_map", "bump_map"):
        if values[field] is not None:
            values[field] = _map_image(values[field], scene_path, f"{where}.{field}")
    emission = tuple(c * values["emission_strength"] for c in values["emission"])
    if not all(math.isfinite(c) and c <= schema.F32_MAX for c in emission):
        raise _Invalid(where, f"emission * emission_strength = {format_number(max(emission))} is beyond "
                              f"the 32-bit float range (up to {schema.F32_MAX:.4g})")
    values["emission"] = emission
    return MaterialSpec(name=name, **_model_kwargs(schema.MATERIAL, values))


def _map_image(file: str, scene_path: Path, where: str) -> TextureSpec:
    """A material's normal or bump map: an image file relative to the scene, read as data."""
    suffix = PurePath(file).suffix
    if suffix.lower() not in schema.MAP_IMAGE_EXTENSIONS:
        raise _Invalid(where, f"unsupported image {_extension_text(suffix)} "
                              f"(expected {_or_list(schema.MAP_IMAGE_EXTENSIONS)})")
    return TextureSpec("bitmap", srgb=False, file=_resolve_file(file, scene_path, where, "texture image",
                                                                schema.MAP_IMAGE_EXTENSIONS))


def _read_materials(raw: object, scene_path: Path, geometry: str) -> tuple[MaterialSpec, ...]:
    table = {} if raw is None else _table(raw, "materials")
    return tuple(_read_material(name, body, scene_path, geometry) for name, body in table.items())


def _read_media(raw: object, scene_path: Path, model_files: ModelFiles) -> tuple[MediumSpec, ...]:
    table = {} if raw is None else _table(raw, "media")
    media = []
    for name, body in table.items():
        where = f"media.{name}"
        values = _read_section(body, schema.MEDIUM, where)
        grids = {}
        if values["type"] == "grid":
            def resolve(field: str) -> Path:
                return _resolve_file(values[field], scene_path, where, "volume grid", VOL_EXTENSIONS)
            try:
                grids = grid_volumes(values, resolve, model_files.ledger)
            except GridFieldError as error:
                raise _Invalid(f"{where}.{error.field}", error.message) from None
        media.append(MediumSpec(name=name, **_model_kwargs(schema.MEDIUM, values), **grids))
    return tuple(media)


def _check_name(kind: str, name: str, known: list[str], none_defined: str, where: str, context: str = "") -> None:
    """A reference to a named definition (a material, a medium) that must exist."""
    if name not in known:
        listed = f"known: {', '.join(known)}" if known else none_defined
        raise _Invalid(where, f"unknown {kind} '{name}'{context} ({listed})")


def _check_medium_name(name: str, media: tuple[MediumSpec, ...], where: str) -> None:
    if name:
        _check_name("medium", name, [m.name for m in media], "no media are defined under [media]", where)


def _read_fog(raw: object, media: tuple[MediumSpec, ...]) -> FogSpec:
    values = _read_section(raw, schema.FOG, "fog")
    if values["type"] == "medium":
        _check_medium_name(values["medium"], media, "fog.medium")
    else:
        values["medium"] = ""
    return FogSpec(**_model_kwargs(schema.FOG, values))


def _read_lights(raw: object, scene_path: Path) -> tuple[LightSpec, ...]:
    lights = []
    for i, body in enumerate([] if raw is None else _tables(raw, "lights")):
        values = _read_section(body, schema.LIGHT, f"lights[{i}]")
        if values.get("texture") is not None:  # an image file, relative to the scene
            values["texture"] = _light_image(values["texture"], scene_path, f"lights[{i}].texture")
        model = LightSpec(kind=values["type"])
        # A field of another kind keeps the model's default (the loader refused it in the table).
        lights.append(LightSpec(**{f.model_attr: getattr(model, f.model_attr) if values[f.name] is None
                                   else values[f.name] for f in schema.LIGHT.fields}))
    return tuple(lights)


def _light_image(file: str, scene_path: Path, where: str) -> TextureSpec:
    suffix = PurePath(file).suffix
    if suffix.lower() not in schema.LIGHT_IMAGE_EXTENSIONS:
        raise _Invalid(where, f"unsupported image {_extension_text(suffix)} "
                              f"(expected {_or_list(schema.LIGHT_IMAGE_EXTENSIONS)})")
    return TextureSpec("bitmap", file=_resolve_file(file, scene_path, where, "texture image",
                                                    schema.LIGHT_IMAGE_EXTENSIONS))


# --- SDF objects -----------------------------------------------------------------------------


def _node_kind(table: dict, where: str) -> NodeKind:
    if "type" not in table:
        raise _Invalid(where, "missing required field 'type'")
    name = _string(table["type"], f"{where}.type")
    kind = schema.NODE_KINDS.get(name)
    if kind is None:
        primitives = ", ".join(k.name for k in schema.PRIMITIVES)
        operators = ", ".join(k.name for k in schema.OPERATORS)
        if name in MESH_OBJECT_KINDS:
            raise _Invalid(where, f"type '{name}' is only allowed in scenes with geometry 'mesh', "
                                  f"not 'sdf' (sdf primitives: {primitives}; operators: {operators})")
        raise _Invalid(where, f"unknown primitive '{name}' (known: {primitives}; operators: {operators})")
    return kind


def _node_fields(kind: NodeKind, top_level: bool) -> tuple[Field, ...]:
    """The fields this node may have: common ones (children for operators, material at top
    level only) followed by the kind's parameters."""
    common = tuple(
        f for f in schema.NODE.fields
        if (f.name != "children" or kind.is_operator) and (f.name != "material" or top_level)
    )
    return common + kind.params


def _read_children(kind: NodeKind, raw: object, where: str, depth: int) -> tuple[SdfNode, ...]:
    children = [] if raw is None else _tables(raw, f"{where}.children")
    count = len(children)
    too_many = kind.max_children is not None and count > kind.max_children
    if count < kind.min_children or too_many:
        raise _Invalid(where, f"'{kind.name}' needs {kind.children_text()}, got {count}")
    return tuple(_read_node(child, f"{where}.children[{i}]", top_level=False, depth=depth + 1)
                 for i, child in enumerate(children))


def _read_node(raw: object, where: str, top_level: bool, depth: int = 1) -> SdfNode:
    """One SDF node and its subtree; `depth` counts the levels down to it (1 at top level)."""
    table = _table(raw, where)
    kind = _node_kind(table, where)
    if depth > schema.MAX_SDF_DEPTH:
        # where names every level above; show its start and end
        place = where if len(where) <= 120 else f"{where[:40]}...{where[-60:]}"
        raise _Invalid(place, f"operators nest deeper than {schema.MAX_SDF_DEPTH} levels")
    # Two common mistakes get a specific message rather than "unknown field".
    if "children" in table and not kind.is_operator:
        raise _Invalid(where, f"primitive '{kind.name}' cannot have children")
    if "material" in table and not top_level:
        raise _Invalid(where, "'material' is only allowed on top-level objects "
                              "(children use their top-level object's material)")
    values = _read_fields(table, _node_fields(kind, top_level), where)
    params = {f.name: values[f.name] for f in kind.params}
    _apply_rules(kind.rules, params, where)
    return SdfNode(
        kind=kind.name,
        params=tuple(sorted(params.items())),
        children=_read_children(kind, values["children"], where, depth) if kind.is_operator else (),
        transform=Transform(values["translate"], values["rotate"], values["scale"]),
        material=values["material"] if top_level else None,
    )


def _object_tables(raw: object) -> list[dict]:
    objects = [] if raw is None else _tables(raw, "objects")
    if not objects:
        raise _Invalid("objects", "the scene has no objects (add at least one [[objects]] table)")
    return objects


def _check_material(name: Optional[str], materials: tuple[MaterialSpec, ...], i: int) -> None:
    if name is not None:
        _check_name("material", name, [m.name for m in materials], "no materials are defined", "",
                     f" in objects[{i}]")


def _read_sdf_objects(raw: object, materials: tuple[MaterialSpec, ...], scene_path: Path) -> dict:
    nodes = []
    for i, body in enumerate(_object_tables(raw)):
        node = _read_node(body, f"objects[{i}]", top_level=True)
        _check_material(node.material, materials, i)
        nodes.append(node)
    return {"sdf_objects": tuple(nodes)}


# --- mesh objects ----------------------------------------------------------------------------


def _mesh_kind(table: dict, where: str) -> MeshKind:
    if "type" not in table:
        raise _Invalid(where, "missing required field 'type'")
    name = _string(table["type"], f"{where}.type")
    kind = schema.MESH_KINDS_BY_NAME.get(name)
    if kind is None:
        known = ", ".join(MESH_OBJECT_KINDS)
        node = schema.NODE_KINDS.get(name)
        if node is not None:
            what = "an sdf operator" if node.is_operator else "an sdf primitive"
            raise _Invalid(where, f"type '{name}' is {what}, only allowed in scenes with geometry "
                                  f"'sdf', not 'mesh' (mesh scenes allow: {known})")
        raise _Invalid(where, f"unknown object type '{name}' (known: {known})")
    return kind


def _generator(table: dict, where: str) -> Generator:
    if "generator" not in table:
        raise _Invalid(where, "missing required field 'generator'")
    field = schema.MESH_KINDS_BY_NAME["generated"].params[0]
    return schema.GENERATORS_BY_NAME[_convert(field, table["generator"], f"{where}.generator")]


def _generator_fields() -> tuple[Field, ...]:
    """Every generator's parameters, each marked as belonging to its generator."""
    return tuple(dataclasses.replace(f, only_for=(g.name,))
                 for g in schema.GENERATORS for f in g.params)


def _expand_scale(kind: MeshKind, scale, raw: object, where: str) -> tuple[float, float, float]:
    if not isinstance(scale, tuple):
        return (scale, scale, scale)
    if kind.uniform_scale_reason and not scale[0] == scale[1] == scale[2]:
        raise _Invalid(f"{where}.scale", f"non-uniform scale {_toml_list(raw)} is not allowed for "
                                         f"type '{kind.name}' ({kind.uniform_scale_reason}); "
                                         "use a uniform scale")
    return scale


def _read_mesh_object(raw: object, where: str, scene_path: Path) -> MeshObject:
    table = _table(raw, where)
    kind = _mesh_kind(table, where)
    fields = schema.MESH_OBJECT.fields + kind.params
    generator = None
    if kind.name == "generated":
        generator = _generator(table, where)
        values = _read_fields(table, fields + _generator_fields(), where, generator.name,
                              selector="generator")
    else:
        values = _read_fields(table, fields, where)
    if kind.needs_material and values["material"] is None:
        raise _Invalid(where, "missing required field 'material'")
    if generator is not None:
        _apply_rules(generator.rules, {f.name: values[f.name] for f in generator.params}, where)
    # The kind's own parameters (radius, size, file) have MeshObject attributes; a generator's
    # parameters (which may share those names) go to `params`.
    shape = {f.name: values[f.name] for f in kind.params}
    _apply_rules(kind.rules, shape, where)
    model = MeshObject(kind=kind.name)
    return MeshObject(
        kind=kind.name,
        file=(_resolve_file(shape["file"], scene_path, where, "model",
                            schema.MESH_FILE_EXTENSIONS) if "file" in shape else None),
        material=values["material"],
        radius=shape.get("radius", model.radius),
        size=shape.get("size", model.size),
        generator=generator.name if generator else None,
        params=tuple(sorted((f.name, values[f.name]) for f in generator.params)) if generator else (),
        profile=shape.get("profile", model.profile),
        degree=shape.get("degree", model.degree),
        spans=shape.get("spans", model.spans),
        sectors=shape.get("sectors", model.sectors),
        translate=values["translate"],
        rotate=values["rotate"],
        scale=_expand_scale(kind, values["scale"], table.get("scale"), where),
    )


def _read_mesh_objects(raw: object, materials: tuple[MaterialSpec, ...], scene_path: Path) -> dict:
    objects = []
    for i, body in enumerate(_object_tables(raw)):
        obj = _read_mesh_object(body, f"objects[{i}]", scene_path)
        _check_material(obj.material, materials, i)
        objects.append(obj)
    return {"mesh_objects": tuple(objects)}


# One reader per geometry kind; each returns the Scene fields holding its objects.
_GEOMETRY_READERS = {"sdf": _read_sdf_objects, "mesh": _read_mesh_objects}


# --- the scene -------------------------------------------------------------------------------


def _build_scene(data: dict, path: Path, model_files: ModelFiles) -> Scene:
    _check_top_level(data)
    header = _read_section(data["scene"], schema.SCENE, "scene")
    camera = _read_section(data.get("camera"), schema.CAMERA, "camera")
    render = _read_render(data.get("render"), header["geometry"])
    environment = _read_environment(data.get("environment"), path)
    lights = _read_lights(data.get("lights"), path)
    materials = _read_materials(data.get("materials"), path, header["geometry"])
    media = _read_media(data.get("media"), path, model_files)
    for m in materials:
        _check_medium_name(m.medium, media, f"materials.{m.name}.medium")
        _check_medium_name(m.outside_medium, media, f"materials.{m.name}.outside_medium")
    fog = _read_fog(data.get("fog"), media)
    geometry = _GEOMETRY_READERS[header["geometry"]](data.get("objects"), materials, path)
    model_material_edits = _read_model_materials(data.get("model_materials"))
    if model_material_edits and header["geometry"] != "mesh":
        raise _Invalid("model_materials", "only a mesh scene reads model files")
    return Scene(
        name=header["name"] if header["name"] is not None else path.stem,
        path=path,
        geometry=header["geometry"],
        camera=CameraSpec(**_model_kwargs(schema.CAMERA, camera)),
        render=render,
        environment=environment,
        materials=materials,
        media=media,
        fog=fog,
        lights=lights,
        description=header["description"],
        model_files=model_files,
        model_material_edits=model_material_edits,
        **geometry,
    )

"""docs/scene-format.md, generated from the scene format's tables (schema.py): the introduction,
one table of fields per section, object kind and generator, and two complete example scenes.

A test keeps the document equal to render_markdown(). Regenerate it with:

    python -c "from renderer.scene.schema_docs import write_markdown; write_markdown()"
"""
from __future__ import annotations

from pathlib import Path

from renderer.scene.mitsuba.format_doc import MITSUBA_SECTION
from renderer.scene.pbrt.format_doc import PBRT_SECTION

from .schema import GENERATORS, MESH_KINDS, MESH_OBJECT, NODE, OPERATORS, PRIMITIVES, SECTIONS
from .schema_types import VALUE_KINDS, Field, Generator, MeshKind, NodeKind, Rule, Section

INTRO = """\
# Scene file format

A scene is a [TOML](https://toml.io) file with the extension `.toml`. Units are metres and
angles are degrees. Colours are linear RGB. Relative file paths (such as an environment map)
are relative to the folder of the scene file.

A scene holds one kind of geometry, named by `[scene] geometry`: `sdf` (signed distance
fields, sphere traced) or `mesh` (triangle meshes with a BVH, plus analytic spheres, discs and
quads, and Bezier surfaces of revolution). The two kinds share `[camera]`, `[render]`, `[environment]` and `[materials]`; they differ
in what `[[objects]]` may hold, and `[render.march]` belongs to `sdf` scenes only.

Only `[scene]` (for its `geometry` field) and at least one object are required; every other
field has the default listed below. The loader is strict: an unknown section or field, a value
of the wrong type (including `true`/`false` where a number is expected), a vector of the wrong
length, `nan` or `inf`, or a value out of range is an error. Every error is one line naming the
file and the place in it, for example:

```text
assets/scenes/x.toml: unknown material 'golde' in objects[2] (known: gold, floor)
assets/scenes/x.toml: materials.glass: unknown field 'iorr' (allowed: type, base_color, roughness, ior, emission, emission_strength)
```

Coming from another renderer? [conventions.md](conventions.md) lists what to match to
reproduce a Mitsuba 3 or pbrt scene: perceptual roughness, the Smith masking term, two-sided
materials, the pixel filter, the environment map's orientation, energy compensation, metals.

This document is generated from `renderer/scene/schema.py` (the format's tables); edit that file,
then run `python -c "from renderer.scene.schema_docs import write_markdown; write_markdown()"`.
"""

EXAMPLE = """\
[scene]
name = "showcase"
description = "A gold sphere and a glass blob on a floor, lit by a park."
geometry = "sdf"

[camera]
position = [0, 1.2, 5]
look_at = [0, 0.5, 0]
fov = 40
aperture = 0.02
focus_distance = 5.0

[render]
width = 960
height = 540
spp = 128
max_depth = -1
integrator = "mis"
seed = 7

[render.march]
max_steps = 400
over_relaxation = 1.5

[environment]
type = "map"
file = "../envmaps/park.exr"
intensity = 1.2
rotation = 90

[materials.gold]
type = "conductor"
base_color = [1.0, 0.78, 0.34]
roughness = 0.2

[materials.glass]
type = "dielectric"
base_color = [1, 1, 1]
roughness = 0.0
ior = 1.5

[materials.floor]
base_color = [0.6, 0.6, 0.6]
roughness = 0.8

[materials.lamp]
emission = [1.0, 0.9, 0.8]
emission_strength = 5.0

[[objects]]
type = "sphere"
material = "gold"
radius = 0.5
translate = [-1, 0.5, 0]

[[objects]]
type = "smooth_union"
material = "glass"
k = 0.2
translate = [1, 0.6, 0]
rotate = [0, 45, 0]
[[objects.children]]
type = "rounded_box"
size = [0.8, 0.8, 0.8]
radius = 0.1
[[objects.children]]
type = "sphere"
radius = 0.5
translate = [0, 0.4, 0]

[[objects]]
type = "repeat"
material = "lamp"
period = [2, 0, 2]
limit = [2, 0, 2]
translate = [0, 3, 0]
[[objects.children]]
type = "torus"
major_radius = 0.3
minor_radius = 0.05

[[objects]]
type = "plane"
material = "floor"
normal = [0, 1, 0]
offset = 0
"""


MESH_EXAMPLE = """\
[scene]
name = "bunny on a table"
description = "A model file, analytic shapes and a generated mesh."
geometry = "mesh"

[camera]
position = [0, 1.5, 4]
look_at = [0, 0.5, 0]
fov = 35

[render]
width = 640
height = 360
spp = 64
max_depth = 8

[environment]
type = "map"
file = "../envmaps/sky.exr"

[materials.copper]
type = "conductor"
base_color = [0.955, 0.638, 0.538]
roughness = 0.25

[materials.plastic]
type = "principled"
base_color = [0.1, 0.3, 0.8]
metallic = 0.0
roughness = 0.3
ior = 1.45

[materials.floor]
base_color = [0.5, 0.5, 0.5]

[materials.lamp]
base_color = [0, 0, 0]
emission = [1, 0.9, 0.8]
emission_strength = 10

[[objects]]
type = "mesh"
file = "../models/bunny.glb"
material = "copper"
translate = [0, 0.45, 0]
rotate = [0, 30, 0]
scale = 0.5

[[objects]]
type = "sphere"
material = "plastic"
radius = 0.3
translate = [1, 0.3, 0]

[[objects]]
type = "quad"
material = "floor"
size = [20, 20]

[[objects]]
type = "disc"
material = "lamp"
radius = 0.5
translate = [0, 3, 0]
rotate = [180, 0, 0]

[[objects]]
type = "generated"
generator = "terrain"
material = "floor"
resolution = 64
size = 20
height = 0.3
seed = 1
translate = [0, -0.35, -15]
scale = [1, 1, 0.5]
"""


def _format_value(value: object) -> str:
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(_format_value(v) for v in value) + "]"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def _default_text(f: Field) -> str:
    if f.default_doc is not None:
        return f.default_doc
    if f.required:
        return "required"
    shared = f"`{_format_value(f.default)}`"
    if not f.type_defaults:
        return shared
    # one clause per value, naming the types that have it, e.g. "`0.0` with `conductor` or `dielectric`"
    types_of = {}
    for kind, value in f.type_defaults:
        types_of.setdefault(_format_value(value), []).append(f"`{kind}`")
    own = "; ".join(f"`{value}` with {' or '.join(kinds)}" for value, kinds in types_of.items())
    return f"{own}; {shared} with the other types"


def _allowed_text(f: Field) -> str:
    if f.allowed_doc is not None:
        return f.allowed_doc
    parts = []
    if f.choices:
        parts.append(", ".join(f"`\"{c}\"`" for c in f.choices))
    if f.kind == "dir3":
        parts.append("non-zero")
    if f.range is not None:
        each = "each component " if f.kind in ("vec3", "vec2", "int3", "dir3", "scale3") else ""
        parts.append(f"{each}{f.range}")
    return "; ".join(parts) or "any"


def _description_text(f: Field) -> str:
    text = f.description
    if f.only_for:
        kinds = " or ".join(f'`type = "{k}"`' for k in f.only_for)
        text += f" Only with {kinds}."
    if f.geometries:
        kinds = " or ".join(f"`{g}`" for g in f.geometries)
        text += f" Only in {kinds} scenes."
    return text


def _field_table(fields: tuple[Field, ...]) -> list[str]:
    lines = ["| Field | Type | Default | Allowed | Description |",
             "| --- | --- | --- | --- | --- |"]
    for f in fields:
        lines.append(f"| `{f.name}` | {VALUE_KINDS[f.kind]} | {_default_text(f)} | "
                     f"{_allowed_text(f)} | {_description_text(f)} |")
    return lines


def _rules_list(rules: tuple[Rule, ...]) -> list[str]:
    return ["", *(f"- {r.text}" for r in rules)] if rules else []


def _section_heading(section: Section) -> str:
    return section.heading if section.heading is not None else f"`[{section.name}]`"


def _items_markdown(fields: tuple[Field, ...]) -> list[str]:
    """The fields of each table of a field of tables (a camera's keyframes, a water surface's waves)."""
    lines = []
    for f in fields:
        if f.items:
            lines += ["", f"Each table of `{f.name}`:", "", *_field_table(f.items)]
    return lines


def _section_markdown(section: Section) -> list[str]:
    return ["", f"## {_section_heading(section)}", "", section.description, "",
            *_field_table(section.fields), *_items_markdown(section.fields), *_rules_list(section.rules)]


def _node_kind_markdown(kind: NodeKind) -> list[str]:
    lines = ["", f"#### `{kind.name}`", "", kind.description]
    if kind.is_operator:
        lines[-1] += f" Takes {kind.children_text()}."
    if kind.params:
        lines += ["", *_field_table(kind.params)]
    else:
        lines += ["", "No parameters."]
    return lines + _rules_list(kind.rules)


def _mesh_kind_markdown(kind: MeshKind) -> list[str]:
    lines = ["", f"#### `{kind.name}`", "", kind.description]
    notes = []
    if kind.needs_material:
        notes.append("Needs `material`.")
    if kind.uniform_scale_reason:
        notes.append(f"Needs a uniform `scale` ({kind.uniform_scale_reason}).")
    if notes:
        lines[-1] += " " + " ".join(notes)
    return lines + ["", *_field_table(kind.params), *_rules_list(kind.rules)]


def _generator_markdown(generator: Generator) -> list[str]:
    return ["", f"#### `{generator.name}`", "", generator.description, "",
            *_field_table(generator.params), *_items_markdown(generator.params), *_rules_list(generator.rules)]


def render_markdown() -> str:
    """The complete text of docs/scene-format.md."""
    lines = [INTRO.rstrip("\n")]
    for section in SECTIONS:
        lines += _section_markdown(section)
    lines += _section_markdown(NODE)
    lines += ["", "### Primitives", "",
              "Primitives sit in their own frame, centred at the origin; y is the axis where "
              "there is one. Lengths must be greater than 0."]
    for kind in PRIMITIVES:
        lines += _node_kind_markdown(kind)
    lines += ["", "### Operators"]
    for kind in OPERATORS:
        lines += _node_kind_markdown(kind)
    lines += _section_markdown(MESH_OBJECT)
    lines += ["", "### Object types", "",
              "Analytic shapes and generated meshes sit in their own frame, centred at the "
              "origin. Lengths must be greater than 0. A field of another type is an error."]
    for kind in MESH_KINDS:
        lines += _mesh_kind_markdown(kind)
    lines += ["", "### Generators", "",
              "The parameters of the chosen `generator` are written as fields of its "
              "`generated` object; a parameter of another generator is an error. Generators "
              "are deterministic: the same parameters give the same mesh."]
    for generator in GENERATORS:
        lines += _generator_markdown(generator)
    lines += ["", "## Complete examples", "",
              "With the scenes in `assets/scenes/`, the maps in `assets/envmaps/` and the models "
              "in `assets/models/`. An `sdf` scene:", "",
              "```toml", EXAMPLE.rstrip("\n"), "```", "",
              "A `mesh` scene:", "",
              "```toml", MESH_EXAMPLE.rstrip("\n"), "```", "", MITSUBA_SECTION.rstrip("\n"),
              "", PBRT_SECTION.rstrip("\n")]
    return "\n".join(lines) + "\n"


# docs/scene-format.md, found from this file: renderer/scene/schema_docs.py -> repository root.
DOC_PATH = Path(__file__).resolve().parents[2] / "docs" / "scene-format.md"


def write_markdown(path: Path = DOC_PATH) -> None:
    Path(path).write_text(render_markdown(), encoding="utf-8")

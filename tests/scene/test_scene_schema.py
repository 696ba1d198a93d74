"""The scene format's tables (renderer/scene/schema.py) against the model's defaults and kinds,
and docs/scene-format.md against the text generated from the schema."""
from __future__ import annotations

import dataclasses

import pytest

from renderer.scene import (
    ENVIRONMENT_KINDS,
    GEOMETRY_KINDS,
    MATERIAL_KINDS,
    SDF_OPERATORS,
    SDF_PRIMITIVES,
    CameraSpec,
    EnvironmentSpec,
    MarchSettings,
    MaterialSpec,
    RenderSettings,
    Scene,
    Transform,
)
from renderer.scene import schema, schema_docs, schema_types
from renderer.scene.model_formats import MESH_EXTENSIONS
from renderer.scene.description import MESH_GENERATORS, MESH_OBJECT_KINDS, MeshObject
from tests.scene.scene_file_helpers import REPO


def _model_defaults(model) -> dict:
    out = {}
    for f in dataclasses.fields(model):
        if f.default is not dataclasses.MISSING:
            out[f.name] = f.default
        elif f.default_factory is not dataclasses.MISSING:
            out[f.name] = f.default_factory()
    return out


SECTION_MODELS = [
    (schema.CAMERA, CameraSpec, set()),
    (schema.RENDER, RenderSettings, {"march"}),
    (schema.MARCH, MarchSettings, set()),
    # a full rotation matrix comes from scene readers that have one (Mitsuba); TOML gives an axis and angle
    (schema.ENVIRONMENT, EnvironmentSpec, {"to_world"}),
    # the name is the table key; textures come from scene readers that have them (Mitsuba), not TOML
    (schema.MATERIAL, MaterialSpec, {"name", "base_color_texture", "opacity_texture", "emission_texture",
                                     "base_color_attribute", "alpha_texture", "alpha_v_texture",
                                     "parameter_textures", "mix", "mix_weight"}),
]


@pytest.mark.parametrize("section, model, not_fields", SECTION_MODELS, ids=lambda x: getattr(x, "name", None))
def test_schema_defaults_equal_model_defaults(section, model, not_fields):
    defaults = _model_defaults(model)
    covered = set()
    for field in section.fields:
        if not field.in_model:
            continue
        covered.add(field.model_attr)
        if field.type_defaults:  # a default per material kind: the model resolves the same one
            for kind in MATERIAL_KINDS:
                assert getattr(model(name="m", kind=kind), field.model_attr) == field.default_for(kind), kind
        elif not field.required:
            assert field.default == defaults[field.model_attr], f"{section.name}.{field.name}"
    # Every model field is described by the schema, and nothing else is.
    assert covered | not_fields == {f.name for f in dataclasses.fields(model)}


def test_required_env_file_matches_model_absent_value():
    assert schema.ENVIRONMENT.field("file").required
    assert EnvironmentSpec().file is None


def test_schema_scene_and_transform_defaults_equal_model():
    assert schema.SCENE.field("description").default == _model_defaults(Scene)["description"]
    transform = Transform()
    for name in ("translate", "rotate", "scale"):
        assert schema.NODE.field(name).default == getattr(transform, name)


def test_schema_kinds_equal_model_kinds():
    assert schema.SCENE.field("geometry").choices == GEOMETRY_KINDS
    assert schema.ENVIRONMENT.field("type").choices == ENVIRONMENT_KINDS
    assert schema.MATERIAL.field("type").choices == MATERIAL_KINDS
    assert tuple(k.name for k in schema.PRIMITIVES) == SDF_PRIMITIVES
    assert tuple(k.name for k in schema.OPERATORS) == SDF_OPERATORS
    assert not any(k.is_operator for k in schema.PRIMITIVES)
    assert all(k.is_operator for k in schema.OPERATORS)
    assert tuple(k.name for k in schema.MESH_KINDS) == MESH_OBJECT_KINDS
    assert schema.MESH_OBJECT.field("type").choices == MESH_OBJECT_KINDS
    assert tuple(g.name for g in schema.GENERATORS) == MESH_GENERATORS
    assert schema.MESH_KINDS_BY_NAME["generated"].params[0].choices == MESH_GENERATORS
    assert schema.MESH_FILE_EXTENSIONS == MESH_EXTENSIONS  # what the mesh loader reads


def test_mesh_schema_defaults_equal_model_defaults():
    model = MeshObject(kind="sphere")
    for name in ("translate", "rotate"):
        assert schema.MESH_OBJECT.field(name).default == getattr(model, name)
    assert (schema.MESH_OBJECT.field("scale").default,) * 3 == model.scale
    assert schema.MESH_OBJECT.field("material").default == model.material
    kinds = schema.MESH_KINDS_BY_NAME
    assert kinds["sphere"].params[0].default == model.radius
    assert kinds["disc"].params[0].default == model.radius
    assert kinds["quad"].params[0].default == model.size
    assert kinds["mesh"].params[0].required and model.file is None
    assert kinds["generated"].params[0].required and model.generator is None and model.params == ()
    # Which kinds need a material and a uniform scale, as the model documents.
    assert [k.name for k in schema.MESH_KINDS if not k.needs_material] == ["mesh"]
    assert [k.name for k in schema.MESH_KINDS if k.uniform_scale_reason] == ["sphere", "disc"]


def test_every_field_has_a_description_and_known_kind():
    fields = [f for s in schema.SECTIONS + (schema.NODE, schema.MESH_OBJECT) for f in s.fields]
    fields += [f for k in schema.NODE_KINDS.values() for f in k.params]
    fields += [f for k in schema.MESH_KINDS + schema.GENERATORS for f in k.params]
    for f in fields:
        assert f.description.strip(), f.name
        assert f.kind in schema_types.VALUE_KINDS, f.name


def test_docs_equal_generated_text():
    doc = REPO / "docs" / "scene-format.md"
    assert doc.read_text(encoding="utf-8") == schema_docs.render_markdown(), (
        "docs/scene-format.md is stale; regenerate it with "
        "python -c \"from renderer.scene.schema_docs import write_markdown; write_markdown()\"")


def test_docs_mention_every_section_field_and_kind():
    text = schema_docs.render_markdown()
    for section in schema.SECTIONS:
        assert section.name in text
        for f in section.fields:
            assert f"`{f.name}`" in text
    for kind in schema.NODE_KINDS:
        assert f"#### `{kind}`" in text
    for kind in schema.MESH_KINDS + schema.GENERATORS:
        assert f"#### `{kind.name}`" in text
        for f in kind.params:
            assert f"`{f.name}`" in text
    assert "## `[[objects]]` in `sdf` scenes" in text
    assert "## `[[objects]]` in `mesh` scenes" in text
    assert 'geometry = "mesh"' in text  # the mesh example


@pytest.mark.parametrize("value, text", [
    (schema_types.Range(1.0, 179.0), "[1, 179]"),
    (schema_types.Range(1.0, 2.0, hi_open=True), "[1, 2)"),
    (schema_types.Range(1.0, 4.0, lo_open=True), "(1, 4]"),
    (schema_types.POSITIVE, "> 0"),
    (schema_types.NON_NEGATIVE, ">= 0"),
    (schema_types.Range(1, also=(-1,)), "-1 or >= 1"),
])
def test_range_text(value, text):
    assert str(value) == text


def test_range_membership():
    depth = schema_types.Range(1, also=(-1,))
    assert -1 in depth and 1 in depth and 100 in depth
    assert 0 not in depth and -2 not in depth
    relax = schema_types.Range(1.0, 2.0, hi_open=True)
    assert 1.0 in relax and 1.999 in relax and 2.0 not in relax

"""Defaults that depend on a material's kind: conductors, dielectrics and plastics are smooth unless a
roughness is given (as in Mitsuba 3 and pbrt), principled, diffuse and null surfaces keep the
shared 0.5; the loader, the plain-data model, the device row and the documentation agree."""
from __future__ import annotations

import pytest

from renderer.materials.kinds import SHARED_ROUGHNESS, default_on, kind, own_defaults
from renderer.scene import MATERIAL_KINDS, MaterialSpec, load_scene, schema
from renderer.scene.schema_docs import render_markdown
from tests.scene.scene_file_helpers import scene_text, write

EXPECTED_ROUGHNESS = {"diffuse": 0.5, "conductor": 0.0, "dielectric": 0.0, "principled": 0.5, "null": 0.5,
                      "plastic": 0.0, "disney": 0.5, "coated": 0.0,
                      "diffuse_transmission": 0.5}


def _loaded(tmp_path, body: str):
    return load_scene(write(tmp_path, scene_text(materials="[materials.m]\n" + body))).materials[0]


@pytest.mark.parametrize("kind_name", MATERIAL_KINDS)
def test_a_material_without_roughness_loads_with_its_kinds_default(tmp_path, kind_name):
    material = _loaded(tmp_path, f'type = "{kind_name}"\n')
    assert material.roughness == EXPECTED_ROUGHNESS[kind_name]


def test_glass_and_metal_are_smooth_and_principled_is_not(tmp_path):
    # Were the old shared default of 0.5 back, the glass would be frosted and the metal brushed.
    assert _loaded(tmp_path, 'type = "dielectric"\nior = 1.5\n').roughness == 0.0
    assert _loaded(tmp_path, 'type = "conductor"\nmetal = "Au"\n').roughness == 0.0
    assert _loaded(tmp_path, 'type = "principled"\nmetallic = 1\n').roughness == SHARED_ROUGHNESS == 0.5
    assert own_defaults("roughness") == {"conductor": 0.0, "dielectric": 0.0, "plastic": 0.0, "coated": 0.0}


@pytest.mark.parametrize("kind_name", ["conductor", "dielectric", "principled"])
def test_a_written_roughness_wins_over_the_kinds_default(tmp_path, kind_name):
    assert _loaded(tmp_path, f'type = "{kind_name}"\nroughness = 0.35\n').roughness == 0.35
    assert _loaded(tmp_path, f'type = "{kind_name}"\nroughness = 0\n').roughness == 0.0
    assert MaterialSpec("m", kind=kind_name, roughness=0.35).roughness == 0.35


def test_python_built_materials_take_the_same_defaults():
    for kind_name, roughness in EXPECTED_ROUGHNESS.items():
        assert MaterialSpec("m", kind=kind_name).roughness == roughness == default_on(kind_name, "roughness", 0.5)
        assert schema.MATERIAL.field("roughness").default_for(kind_name) == roughness


def test_smooth_defaults_compile_no_roughness_compensation():
    """A default glass or metal is a delta lobe: its device row has roughness 0, so the scene needs
    none of the rough-surface energy compensation."""
    from renderer.materials.table import MaterialRows

    rows = MaterialRows()
    rows.add_spec(MaterialSpec("glass", kind="dielectric"))
    rows.add_spec(MaterialSpec("gold", kind="conductor", metal="Au"))
    assert [r["roughness"] for r in rows.rows] == [0.0, 0.0]
    assert not rows.uses()["rough"]
    assert kind("dielectric").compensation == kind("conductor").compensation == "rough"


def test_the_documentation_gives_the_defaults_per_kind():
    row = next(line for line in render_markdown().splitlines() if line.startswith("| `roughness` |"))
    assert "`0.0` with `conductor` or `dielectric` or `plastic` or `coated`; `0.5` with the other types" in row

"""renderer/editing.py: values kept within the scene format's ranges with a line per change, a
material replaced by name, and the history of edits undone, redone and reset."""
from __future__ import annotations

import math

import pytest

from renderer.editing import (Edit, EditHistory, allowed_range, canonical, clamped, material_named,
                              with_material)
from renderer.scene.description import CameraSpec, EnvironmentSpec, MaterialSpec, RenderSettings, Scene


def test_values_outside_the_format_are_brought_within_it_and_said():
    spec, notes = clamped(MaterialSpec("m", kind="dielectric", roughness=1.5, ior=0.5, base_color=(2.0, -1.0, 0.5)))
    assert spec.roughness == 1.0 and spec.base_color == (1.0, 0.0, 0.5)
    assert spec.ior > 1.0 and spec.ior == math.nextafter(1.0, 2.0)  # the index's range is open at 1
    assert "roughness 1.5 -> 1 (allowed [0, 1])" in notes and any(n.startswith("ior 0.5 -> 1") for n in notes)
    assert any(n.startswith("base_color (2, -1, 0.5) -> (1, 0, 0.5)") for n in notes) and len(notes) == 3
    same, none = clamped(MaterialSpec("m", roughness=0.3))
    assert same == MaterialSpec("m", roughness=0.3) and none == []
    assert str(allowed_range("roughness")) == "[0, 1]" and allowed_range("no such field") is None


def test_a_material_is_replaced_by_name():
    scene = Scene(name="s", path=None, geometry="mesh", camera=CameraSpec(), render=RenderSettings(),
                  environment=EnvironmentSpec(), materials=(MaterialSpec("a"), MaterialSpec("b")))
    edited = with_material(scene, MaterialSpec("b", kind="conductor"))
    assert [m.kind for m in edited.materials] == ["diffuse", "conductor"] and material_named(edited, "a").kind == "diffuse"
    with pytest.raises(KeyError, match="no material 'c'"):
        with_material(scene, MaterialSpec("c"))


def test_undo_redo_and_the_material_as_loaded():
    a0, a1, a2 = (MaterialSpec("a", roughness=r) for r in (0.1, 0.2, 0.3))
    history = EditHistory()
    assert history.undo() is None and history.redo() is None
    history.record(Edit(a0, a1))
    history.record(Edit(a1, a2))
    assert history.undo() == a1 and history.undo() == a0 and history.undo() is None
    assert history.redo() == a1
    history.record(Edit(a1, MaterialSpec("a", roughness=0.9)))  # a new edit drops the redo
    assert history.redo() is None and history.as_loaded("a") == a0 and history.as_loaded("b") is None


def test_a_conductor_keeps_one_fresnel_description():
    gold = canonical(MaterialSpec("m", kind="conductor", metal="Au", base_color=(0.1, 0.2, 0.3), eta=(1, 1, 1),
                                  k=(2, 2, 2)))
    assert gold.base_color == MaterialSpec("x").base_color and gold.eta is None and gold.metal == "Au"
    indexed = canonical(MaterialSpec("m", kind="conductor", eta=(1, 1, 1), k=(2, 2, 2), edge_tint=(0.5, 0.5, 0.5)))
    assert indexed.eta == (1, 1, 1) and indexed.edge_tint == (1.0, 1.0, 1.0)
    tinted = MaterialSpec("m", kind="conductor", base_color=(0.1, 0.2, 0.3))
    assert canonical(tinted) is tinted


def test_a_dragged_slider_is_one_edit_for_a_material_and_for_the_environment():
    history = EditHistory()
    a = [MaterialSpec("a", roughness=r) for r in (0.1, 0.2, 0.3)]
    sky = [EnvironmentSpec(kind="sky", intensity=i) for i in (1.0, 1.5, 2.0)]
    for edits in (a, sky):
        history.record(Edit(edits[0], edits[1]), merge=True)
        history.record(Edit(edits[1], edits[2]), merge=True)
    assert len(history.done) == 2 and history.done[1].name == "environment"
    assert history.undo() == sky[0] and history.undo() == a[0]

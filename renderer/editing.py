"""Editing a scene's materials while it renders: an edit replaces one material of the scene by
name, its values kept within the ranges the scene format allows, and a history undoes and redoes
edits. The Renderer adopts the edited scene in place (Renderer.edit_materials).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

from renderer.scene.conductor_fresnel import canonical  # noqa: F401 (the editors' name for it)
from renderer.scene.description import EnvironmentSpec, LightSpec, MaterialSpec, Scene
from renderer.scene.schema import ENVIRONMENT as ENVIRONMENT_SECTION, LIGHT, MATERIAL, MODEL_MATERIAL

ENVIRONMENT = "environment"  # the history's name for the environment's edits


@dataclass(frozen=True)
class SceneLight:
    """One of the scene's point, spot, directional or projector lights, by its place in the list."""

    index: int
    spec: LightSpec

    @property
    def name(self) -> str:
        return f"lights[{self.index}]"


@dataclass(frozen=True)
class ModelMaterialEdit:
    """A model file's own material as the scene edits it: its number among the model materials
    and the factors set ((PbrMaterial attribute, value) pairs, sorted; none: the file's)."""

    index: int
    changes: tuple = ()

    @property
    def name(self) -> str:
        return f"model material {self.index}"


def model_material_edit(scene: Scene, index: int) -> ModelMaterialEdit:
    """The scene's edit of model material `index` (no changes where it has none)."""
    return ModelMaterialEdit(index, dict(scene.model_material_edits).get(index, ()))


def with_model_material(scene: Scene, edit: ModelMaterialEdit) -> Scene:
    edits = {i: changes for i, changes in scene.model_material_edits if i != edit.index}
    if edit.changes:
        edits[edit.index] = tuple(sorted(edit.changes))
    return replace(scene, model_material_edits=tuple(sorted(edits.items())))


def with_light(scene: Scene, light: SceneLight) -> Scene:
    lights = list(scene.lights)
    lights[light.index] = light.spec
    return replace(scene, lights=tuple(lights))


@dataclass(frozen=True)
class Edit:
    """One material of a scene, or its environment, before and after an edit."""

    before: object  # MaterialSpec or EnvironmentSpec
    after: object

    @property
    def name(self) -> str:
        """The material's name, ENVIRONMENT, or a light's `lights[i]`."""
        return ENVIRONMENT if isinstance(self.after, EnvironmentSpec) else self.after.name

    def fields_changed(self) -> frozenset:
        before, after = self.before, self.after
        if isinstance(after, ModelMaterialEdit):
            was, now = dict(before.changes), dict(after.changes)
            return frozenset(k for k in {*was, *now} if was.get(k) != now.get(k))
        if isinstance(after, SceneLight):
            before, after = before.spec, after.spec
        return frozenset(f.name for f in fields(type(before)) if getattr(before, f.name) != getattr(after, f.name))


def with_material(scene: Scene, spec: MaterialSpec) -> Scene:
    """The scene with its material of that name replaced by `spec`."""
    names = [m.name for m in scene.materials]
    if spec.name not in names:
        raise KeyError(f"the scene has no material '{spec.name}'")
    return replace(scene, materials=tuple(spec if m.name == spec.name else m for m in scene.materials))


def material_named(scene: Scene, name: str) -> MaterialSpec:
    return scene.materials[scene.material_index(name)]


def allowed_range(name: str):
    """The scene format's range of a material field (renderer/scene/schema.py), or None."""
    for f in MATERIAL.fields:
        if f.model_attr == name or f.name == name:
            return f.range
    return None


def clamped(spec):
    """`spec` (a MaterialSpec, an EnvironmentSpec or a SceneLight) with every numeric field brought
    within its range in the scene format, and a line per value changed ("roughness 1.5 -> 1
    (allowed [0, 1])")."""
    if isinstance(spec, ModelMaterialEdit):
        return _clamped_model_material(spec)
    if isinstance(spec, SceneLight):
        light, notes = clamped(spec.spec)
        light, more = clamped_light(light)
        return replace(spec, spec=light), notes + more
    changes, notes = {}, []
    section = (ENVIRONMENT_SECTION if isinstance(spec, EnvironmentSpec) else LIGHT if isinstance(spec, LightSpec)
               else MATERIAL)
    for f in section.fields:
        if f.range is None or not f.in_model or not hasattr(spec, f.model_attr):
            continue
        value = getattr(spec, f.model_attr)
        if isinstance(value, bool) or value is None:
            continue
        if isinstance(value, (int, float)):
            fixed = _within(float(value), f.range)
            if fixed != value:
                changes[f.model_attr] = type(value)(fixed) if isinstance(value, int) else fixed
        elif isinstance(value, tuple) and all(isinstance(c, (int, float)) for c in value):
            fixed = tuple(_within(float(c), f.range) for c in value)
            if fixed != tuple(float(c) for c in value):
                changes[f.model_attr] = fixed
        else:
            continue
        if f.model_attr in changes:
            notes.append(f"{f.name} {_text(value)} -> {_text(changes[f.model_attr])} (allowed {f.range})")
    return (replace(spec, **changes) if changes else spec), notes


def _clamped_model_material(edit: ModelMaterialEdit) -> tuple:
    fields_by_attr = {f.model_attr: f for f in MODEL_MATERIAL.fields}
    changes, notes = [], []
    for attr, value in edit.changes:
        f = fields_by_attr[attr]
        fixed = (tuple(_within(float(c), f.range) for c in value) if isinstance(value, tuple)
                 else _within(float(value), f.range))
        if fixed != value:
            notes.append(f"{f.name} {_text(value)} -> {_text(fixed)} (allowed {f.range})")
        changes.append((attr, fixed))
    return ModelMaterialEdit(edit.index, tuple(sorted(changes))), notes


def clamped_light(light: LightSpec) -> tuple:
    """A light's cone and direction made valid: beam_width at most cutoff_angle, the direction of
    unit length (a zero one pointing down); with a line per change of meaning."""
    notes, changes = [], {}
    if light.beam_width is not None and light.beam_width > light.cutoff_angle:
        changes["beam_width"] = light.cutoff_angle
        notes.append(f"beam_width {light.beam_width:g} -> {light.cutoff_angle:g} (at most cutoff_angle)")
    length = math.hypot(*light.direction)
    if not length > 0.0 or not math.isfinite(length):
        changes["direction"] = (0.0, -1.0, 0.0)
        notes.append(f"direction {_text(light.direction)} -> (0, -1, 0) (a direction needs a finite length)")
    elif abs(length - 1.0) > 1e-12:  # unit length as the scene format reads it (one already is: kept)
        changes["direction"] = tuple(c / length for c in light.direction)
    return (replace(light, **changes) if changes else light), notes


def _within(x: float, r) -> float:
    if not math.isfinite(x):
        x = r.lo if r.lo is not None else 0.0
    if x in r.also:
        return x
    if r.lo is not None and (x < r.lo or (r.lo_open and x <= r.lo)):
        x = math.nextafter(r.lo, math.inf) if r.lo_open else r.lo
    if r.hi is not None and (x > r.hi or (r.hi_open and x >= r.hi)):
        x = math.nextafter(r.hi, -math.inf) if r.hi_open else r.hi
    return x


def _text(value) -> str:
    if isinstance(value, tuple):
        return "(" + ", ".join(f"{c:g}" for c in value) + ")"
    return f"{value:g}"


@dataclass
class EditHistory:
    """Edits in the order made; undo walks back, redo forward again, a new edit drops what was
    undone. `original` keeps each material as the scene file had it (reset)."""

    done: list[Edit] = field(default_factory=list)
    undone: list[Edit] = field(default_factory=list)
    original: dict = field(default_factory=dict)

    def record(self, edit: Edit, merge: bool = False) -> None:
        """Add an edit; with `merge`, one that goes on changing the same fields of the material
        the last edit changed (a slider being dragged) extends that edit instead, so one undo
        takes back the whole gesture."""
        self.original.setdefault(edit.name, edit.before)
        last = self.done[-1] if self.done else None
        if (merge and last is not None and last.name == edit.name and last.after == edit.before
                and last.fields_changed() == edit.fields_changed()):
            self.done[-1] = Edit(last.before, edit.after)
        else:
            self.done.append(edit)
        self.undone.clear()

    def undo(self):
        """The material (or environment) to restore, or None with nothing to undo."""
        if not self.done:
            return None
        edit = self.done.pop()
        self.undone.append(edit)
        return edit.before

    def redo(self):
        if not self.undone:
            return None
        edit = self.undone.pop()
        self.done.append(edit)
        return edit.after

    def as_loaded(self, name: str):
        """The material (or, by ENVIRONMENT, the environment) as the scene file had it, or None
        where it was never edited."""
        return self.original.get(name)

"""The viewer's edits of the scene on screen: what was picked, each edit applied to its Renderer at
once (in place where it can be, renderer/renderer.py edit_materials; else on a Renderer built for
the edited scene), undo and redo, the material as the file had it, and saving.

It holds no window: the window (viewer/window.py) calls it on a click, a key or a panel change,
and headless tests drive it the same way.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Callable, Optional

from renderer.camera import CameraFrame
from renderer.editing import (Edit, EditHistory, ModelMaterialEdit, SceneLight, canonical, clamped, material_named,
                              model_material_edit, with_light, with_material, with_model_material)
from renderer.picking import Pick, pick
from renderer.renderer import Renderer
from renderer.scene.description import EnvironmentSpec, MaterialSpec, Scene
from renderer.scene.edit_saving import edited_path, save_edits


class SceneEditor:
    def __init__(self, loaded: Scene, rebuild: Callable[[Scene], Renderer]):
        """loaded: the scene as its file gave it; rebuild(scene): a Renderer for an edited scene
        where the one on screen cannot take the edit in place (a texture's change)."""
        self.loaded = loaded
        self.rebuild = rebuild
        self.history = EditHistory()
        self.picked: Optional[Pick] = None
        self.notes: list[str] = []  # what the last edit clamped, one line each
        self.recompiled = False  # whether the last edit built a new Renderer
        self.environment_open = False  # the environment's panel (a click on nothing opens it)
        self.light_open: Optional[int] = None  # the panel of scene.lights[i] (from the environment's)

    # --- picking ------------------------------------------------------------------------------
    def pick(self, renderer: Renderer, camera: CameraFrame, u: float, v: float,
             integrator: Optional[str] = None) -> Optional[Pick]:
        self.picked = pick(renderer, camera, u, v, integrator)
        self.environment_open = self.picked is None
        self.light_open = None
        self.notes = []
        return self.picked

    def open_light(self, index: int) -> None:
        """The panel of the scene's point, spot, directional or projector light `index` (no ray
        can hit them: the environment's panel lists them)."""
        self.picked, self.environment_open, self.light_open, self.notes = None, False, index, []

    @property
    def panel_open(self) -> bool:
        return self.picked is not None or self.environment_open or self.light_open is not None

    def close(self) -> None:
        self.picked, self.environment_open, self.light_open = None, False, None

    def picked_material(self, scene: Scene) -> Optional[MaterialSpec]:
        """The picked material as it is now (None: nothing picked, or a model file's own)."""
        if self.picked is None or not self.picked.editable:
            return None
        return material_named(scene, self.picked.material_name)

    # --- edits --------------------------------------------------------------------------------
    def apply(self, renderer: Renderer, spec, record: bool = True, merge: bool = False) -> Renderer:
        """Show `spec` (a material of the scene, by name, or its environment), its values brought
        within the scene format's ranges; returns the Renderer that shows it (this one, or one
        built anew). `merge`: a step of the same change as the last edit (a slider dragged) is one
        edit."""
        spec, self.notes = clamped(spec)
        self.recompiled = False
        if isinstance(spec, ModelMaterialEdit):
            before = model_material_edit(renderer.scene, spec.index)
            if spec == before:
                return renderer
            scene = with_model_material(renderer.scene, spec)
            in_place = renderer.edit_materials(scene)
        elif isinstance(spec, SceneLight):
            before = SceneLight(spec.index, renderer.scene.lights[spec.index])
            if spec == before:
                return renderer
            scene = with_light(renderer.scene, spec)
            in_place = renderer.edit_lights(scene.lights)
        elif isinstance(spec, EnvironmentSpec):
            before = renderer.scene.environment
            if spec == before:
                return renderer
            in_place = renderer.edit_environment(spec)
            scene = replace(renderer.scene, environment=spec)
        else:
            spec = canonical(spec)
            before = material_named(renderer.scene, spec.name)
            if spec == before:
                return renderer
            scene = with_material(renderer.scene, spec)
            in_place = renderer.edit_materials(scene)
        if not in_place:
            renderer = self.rebuild(scene)
            self.recompiled = True
        if record:
            self.history.record(Edit(before, spec), merge)
        return renderer

    def undo(self, renderer: Renderer) -> Renderer:
        spec = self.history.undo()
        return renderer if spec is None else self.apply(renderer, spec, record=False)

    def redo(self, renderer: Renderer) -> Renderer:
        spec = self.history.redo()
        return renderer if spec is None else self.apply(renderer, spec, record=False)

    def reset_material(self, renderer: Renderer) -> Renderer:
        """The picked material (or the open environment or light) back to the file's (an edit
        itself: undo brings the change back)."""
        if self.light_open is not None:
            return self.apply(renderer, SceneLight(self.light_open, self.loaded.lights[self.light_open]))
        if self.environment_open:
            return self.apply(renderer, self.loaded.environment)
        if self.picked is not None and self.picked.model_material >= 0:
            return self.apply(renderer, model_material_edit(self.loaded, self.picked.model_material))
        if self.picked is None or not self.picked.editable:
            return renderer
        return self.apply(renderer, material_named(self.loaded, self.picked.material_name))

    # --- saving -------------------------------------------------------------------------------
    @property
    def edited(self) -> bool:
        return bool(self.history.done)

    def save_path(self) -> Path:
        """Where save() writes by default (renderer/scene/edit_saving.py edited_path)."""
        return edited_path(Path(self.loaded.path))

    @property
    def saves_over_its_file(self) -> bool:
        """Whether the default save is the scene's own file (a saved `_edited.toml` opened again)."""
        return self.save_path().resolve() == Path(self.loaded.path).resolve()

    def save(self, scene: Scene, path: Optional[Path] = None, overwrite: bool = False) -> Path:
        """Write the edited scene beside its file (renderer.scene.edit_saving.py)."""
        return save_edits(scene, self.loaded, path, overwrite)

"""What is under a pixel: the camera ray's first hit (Renderer.pick) told in the scene's terms, the
object of the scene file, its material by name and kind, the point, its distance and texture
coordinates. The viewer shows it and edits the material it names (renderer/editing.py)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from renderer.camera import CameraFrame
from renderer.renderer import Renderer, SurfaceHit


@dataclass(frozen=True)
class Pick:
    hit: SurfaceHit
    object_index: int  # in Scene.mesh_objects or Scene.sdf_objects; -1 where not known
    object_label: str  # e.g. "objects[7] (quad)"
    material_index: int  # in Scene.materials; -1 for a model file's own material
    material_name: str
    material_kind: str
    model_material: int = -1  # a model file's own material: its number among them (model_materials.<i>)

    @property
    def editable(self) -> bool:
        """Whether the material is one of the scene's (a model file's own has its own panel)."""
        return self.material_index >= 0

    def where(self) -> str:
        """The hit: "at (x, y, z), 3.88 m, uv (u, v)"."""
        h = self.hit
        point = ", ".join(f"{c:.3g}" for c in h.point)
        return f"at ({point}), {h.distance:.3g} m, uv ({h.uv[0]:.3g}, {h.uv[1]:.3g})"

    def describe(self) -> str:
        """One line for the HUD."""
        return f"{self.object_label}: material '{self.material_name}' ({self.material_kind}), {self.where()}"


def pick(renderer: Renderer, camera: CameraFrame, u: float, v: float,
         integrator: Optional[str] = None) -> Optional[Pick]:
    """The scene's object and material under (u, v) in [0,1]^2 of the film (y up), or None."""
    hit = renderer.pick(camera, u, v, integrator)
    if hit is None:
        return None
    scene = renderer.scene
    index = int(renderer.geometry.objects_of(np.array([hit.primitive]))[0])
    objects = scene.mesh_objects if scene.geometry == "mesh" else scene.sdf_objects
    label = f"objects[{index}] ({_object_kind(objects[index])})" if 0 <= index < len(objects) else "an object"
    if 0 <= hit.material < len(scene.materials):
        spec = scene.materials[hit.material]
        return Pick(hit, index, label, hit.material, spec.name, spec.kind)
    # a model file's own material (glTF's are shaded as principled), numbered after the scene's
    number = hit.material - len(scene.materials)
    return Pick(hit, index, label, -1, f"model material {number}", "principled", model_material=number)


def _object_kind(obj) -> str:
    if getattr(obj, "file", None) is not None:
        return f"{obj.kind} {obj.file.name}"
    return obj.kind

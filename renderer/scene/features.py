"""What a scene calls for. Kernels are compiled per Features, so nothing unused is simulated.

Features names *kinds* (BSDF kinds, SDF primitive and operator kinds, environment kind, lens model),
never instances: adding a tenth sphere to a scene with spheres compiles nothing new.
"""
from __future__ import annotations

from dataclasses import dataclass, fields, replace

from renderer.scene.model import MATERIAL_KINDS, SDF_OPERATORS, SDF_PRIMITIVES, Scene


@dataclass(frozen=True)
class Features:
    geometry: str = "sdf"
    has_diffuse: bool = False
    has_conductor: bool = False
    has_dielectric: bool = False
    has_emission: bool = False
    environment: str = "sky"  # "map" | "sky" | "constant"
    depth_of_field: bool = False
    sdf_primitives: frozenset = frozenset()
    sdf_operators: frozenset = frozenset()

    def active_effects(self) -> list[str]:
        """Short names for the HUD and `app.py info`."""
        names = [k for k, on in (("diffuse", self.has_diffuse), ("conductor", self.has_conductor),
                                  ("glass", self.has_dielectric), ("emission", self.has_emission),
                                  ("depth of field", self.depth_of_field)) if on]
        names.append(f"env:{self.environment}")
        return names

    def describe(self) -> dict:
        out = {}
        for f in fields(self):
            v = getattr(self, f.name)
            out[f.name] = sorted(v) if isinstance(v, frozenset) else v
        return out

    def with_everything(self) -> "Features":
        """Every optional effect of this geometry kind switched on (for the cost benchmark)."""
        return replace(self, has_diffuse=True, has_conductor=True, has_dielectric=True, has_emission=True,
                       depth_of_field=True, sdf_primitives=frozenset(SDF_PRIMITIVES),
                       sdf_operators=frozenset(SDF_OPERATORS) if self.geometry == "sdf" else frozenset())


def scene_features(scene: Scene, aperture: float | None = None) -> Features:
    """Features of a scene; `aperture` overrides the scene camera's (the viewer's lens slider)."""
    kinds = {m.kind for m in scene.materials}
    unknown = kinds - set(MATERIAL_KINDS)
    if unknown:
        raise ValueError(f"unknown material kinds {sorted(unknown)}")
    used_materials = {n.material for n in scene.sdf_objects}
    used = [m for m in scene.materials if m.name in used_materials] or list(scene.materials)
    nodes = [node for top in scene.sdf_objects for node in top.walk()]
    lens = scene.camera.aperture if aperture is None else aperture
    return Features(
        geometry=scene.geometry,
        has_diffuse=any(m.kind == "diffuse" for m in used),
        has_conductor=any(m.kind == "conductor" for m in used),
        has_dielectric=any(m.kind == "dielectric" for m in used),
        has_emission=any(m.is_emissive for m in used),
        environment=scene.environment.kind,
        depth_of_field=lens > 0.0,
        sdf_primitives=frozenset(n.kind for n in nodes if n.kind in SDF_PRIMITIVES),
        sdf_operators=frozenset(n.kind for n in nodes if n.kind in SDF_OPERATORS),
    )

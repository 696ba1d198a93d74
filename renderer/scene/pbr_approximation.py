"""A model file's glTF material as the closest of the scene format's three simple kinds.

For renderers that do not (yet) evaluate the full metallic-roughness model; Lantern's own renders
use every layer (renderer.materials.table).
"""
from __future__ import annotations

from renderer.scene.description import MaterialSpec
from renderer.scene.mesh_model import PbrMaterial


def approximate_spec(material: PbrMaterial) -> MaterialSpec:
    """The closest of the renderer's three simple kinds, ignoring textures.

    transmission >= 0.5 -> dielectric (tint = base colour), else metallic >= 0.5 -> conductor
    (F0 = base colour), else diffuse (albedo = base colour). Roughness and emission carry over.
    Meant for renderers that do not (yet) evaluate the full metallic-roughness model.
    """
    rgb = tuple(float(c) for c in material.base_color_factor[:3])
    if material.transmission_factor >= 0.5:
        kind = "dielectric"
    elif material.metallic_factor >= 0.5:
        kind = "conductor"
    else:
        kind = "diffuse"
    return MaterialSpec(
        name=material.name,
        kind=kind,
        base_color=rgb,
        roughness=float(min(max(material.roughness_factor, 0.0), 1.0)),
        ior=float(material.ior),
        emission=tuple(float(c) for c in material.emissive_factor),
    )

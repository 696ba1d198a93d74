"""Mitsuba 3's `mesh_attribute` texture made into a material's `MeshAttributeColor`: a colour
read per vertex or per face from the PLY mesh a shape draws (renderer/scene/mesh_attributes.py).

  on a base colour     diffuse `reflectance`, plastics' `diffuse_reflectance`, principled
                       `base_color` (also inside twosided, mask, bumpmap, normalmap): the colour
                       is the attribute times the texture's `scale`
  blendbsdf weight     a blend of two diffuse BSDFs with plain colours is one diffuse BSDF whose
                       colour is (1 - w) r0 + w r1: w a number, or an attribute per vertex or face

Anything else that holds a mesh_attribute is the builder's to warn about.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from renderer.scene.description import MaterialSpec, MeshAttributeColor
from renderer.scene.mitsuba.plugins import Plugin

BASE_COLOUR_PARAMETER = {"diffuse": "reflectance", "plastic": "diffuse_reflectance",
                         "roughplastic": "diffuse_reflectance", "principled": "base_color",
                         "principledthin": "base_color"}
WRAPPERS = ("twosided", "mask", "bumpmap", "normalmap")  # BSDFs that shade with the one inside


def is_mesh_attribute(value) -> bool:
    return isinstance(value, Plugin) and value.kind == "texture" and value.type == "mesh_attribute"


def attribute_colour(builder, texture: Plugin, offset=(0.0, 0.0, 0.0), scale=(1.0, 1.0, 1.0)) -> MeshAttributeColor:
    """The MeshAttributeColor offset + scale * (the texture's scale * the attribute)."""
    builder.visit(texture)
    name = texture.text("name")
    if not name:
        raise texture.error("needs the name of a mesh attribute (vertex_... or face_...)")
    if not name.startswith(("vertex_", "face_")):
        raise texture.error(f"mesh attribute '{name}' is neither vertex_... nor face_...")
    factor = texture.number("scale", 1.0)
    return MeshAttributeColor(name, offset=tuple(float(c) for c in offset),
                              scale=tuple(float(c) * factor for c in scale))


def with_mesh_attribute(builder, spec: MaterialSpec, bsdf: Plugin) -> MaterialSpec:
    """`spec` with the mesh attribute its BSDF (or the BSDF a wrapper shades with) reads as its base
    colour; `spec` itself where it reads none."""
    while bsdf.type in WRAPPERS and bsdf.objects("bsdf"):
        bsdf = bsdf.objects("bsdf")[0]
    parameter = BASE_COLOUR_PARAMETER.get(bsdf.type)
    texture = bsdf.properties.get(parameter) if parameter else None
    if not is_mesh_attribute(texture):
        return spec
    bsdf.used.add(parameter)
    return replace(spec, base_color=(1.0, 1.0, 1.0), base_color_texture=None,
                   base_color_attribute=attribute_colour(builder, texture))


def blended_diffuse(builder, bsdf: Plugin) -> MaterialSpec | None:
    """A blendbsdf of two diffuse BSDFs with plain colours as one diffuse spec; None for any other
    blend (the builder's to approximate)."""
    nested = bsdf.objects("bsdf")
    weight = bsdf.properties.get("weight", 0.5)
    if len(nested) != 2 or any(b.type != "diffuse" or _textured(b.properties.get("reflectance")) for b in nested):
        return None
    if not (is_mesh_attribute(weight) or _number(weight)):
        return None
    bsdf.used.add("weight")
    r0, r1 = (np.array(builder.colour(builder.visit(b), "reflectance", (0.5, 0.5, 0.5))) for b in nested)
    if is_mesh_attribute(weight):
        return MaterialSpec("", "diffuse", base_color=(1.0, 1.0, 1.0), sidedness="back_black",
                            base_color_attribute=attribute_colour(builder, weight, offset=r0, scale=r1 - r0))
    w = float(weight)
    if not 0.0 <= w <= 1.0:
        raise bsdf.error(f"weight {w:g} is not between 0 and 1")
    return MaterialSpec("", "diffuse", base_color=tuple(float(c) for c in (1.0 - w) * r0 + w * r1),
                        sidedness="back_black")


def _textured(value) -> bool:
    return isinstance(value, Plugin)


def _number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)

"""A conductor's Fresnel comes from one of three descriptions (the scene format's rule,
schema_checks.check_conductor_fresnel): a named `metal`, a complex index `eta` with `k`, or
`base_color` with `edge_tint` (Hoffman's F82). The fields of the others then shade nothing."""
from __future__ import annotations

from dataclasses import replace

from renderer.scene.description import MaterialSpec

FRESNEL_DESCRIPTIONS = (("metal",), ("eta", "k"), ("base_color", "edge_tint"))


def description_of(spec: MaterialSpec) -> tuple:
    """The description a conductor's Fresnel comes from: a named metal, else eta and k, else its
    colours."""
    metal, index, colours = FRESNEL_DESCRIPTIONS
    return metal if spec.metal else index if spec.eta is not None else colours


def other_fields(description: tuple) -> tuple:
    """The fields of the descriptions other than `description`."""
    return tuple(name for d in FRESNEL_DESCRIPTIONS if d != description for name in d)


def canonical(spec: MaterialSpec, description: tuple | None = None) -> MaterialSpec:
    """`spec` as the scene format writes it: a conductor's fields outside its Fresnel description
    (`description`, default the one it uses) at their defaults, so that a saved edit reads back as
    the same material (they would not shade it anyway). Other kinds as they are."""
    if spec.kind != "conductor":
        return spec
    plain = MaterialSpec(spec.name)
    dropped = {name: getattr(plain, name) for name in other_fields(description or description_of(spec))
               if getattr(spec, name) != getattr(plain, name)}
    return replace(spec, **dropped) if dropped else spec

"""Mitsuba 3 BSDF plugins made into Lantern material specs.

Mitsuba's BSDFs are one-sided unless they transmit: diffuse, conductors and plastics are black
from behind (sidedness "back_black"); `twosided` makes the BSDF it wraps shade both sides alike;
dielectrics, thin dielectrics, principledthin and null are two-sided by nature, and principled
(Lantern's `disney` kind) shades its back side itself. Rough BSDFs keep Mitsuba's microfacet model: GGX or Beckmann with Smith's separable
masking (renderer/materials/microfacet.py). `mask` becomes stochastic coverage (opacity, or its
texture); `normalmap` and `bumpmap` tilt the shading normal of the BSDF inside (surface_maps.py).
The builder (scene_builder.py) supplies the value readers (colours, textures, scalars) and the
warnings.
"""
from __future__ import annotations

import math
from dataclasses import replace

from renderer.materials.kinds import MAX_MIX_DEPTH
from renderer.materials.metals import metal_names
from renderer.scene.description import MaterialSpec, TextureSpec
from renderer.scene.mitsuba.ior_names import IOR_NAMES
from renderer.scene.mitsuba.mesh_attribute_textures import blended_diffuse
from renderer.scene.mitsuba.plugins import Plugin
from renderer.scene.mitsuba.scene_warnings import warn
from renderer.scene.mitsuba.surface_maps import mapped_spec

DEFAULT_REFLECTANCE = (0.5, 0.5, 0.5)  # Mitsuba's diffuse and plastics
DEFAULT_GLASS_IOR = 1.5046  # Mitsuba's dielectrics: bk7
DEFAULT_PLASTIC_IOR = IOR_NAMES["polypropylene"]  # Mitsuba's plastics
# Mitsuba's principled and principledthin parameters (name, default) that Lantern's `disney`
# kind takes as they are (DISNEY_FIELDS renames the one it names otherwise).
_SHARED_PRINCIPLED = (("roughness", 0.5), ("anisotropic", 0.0), ("spec_trans", 0.0), ("sheen", 0.0),
                      ("sheen_tint", 0.0), ("flatness", 0.0), ("spec_tint", 0.0))
PRINCIPLED_PARAMS = (*_SHARED_PRINCIPLED, ("metallic", 0.0), ("clearcoat", 0.0), ("clearcoat_gloss", 0.0))
PRINCIPLEDTHIN_PARAMS = (*_SHARED_PRINCIPLED, ("diff_trans", 0.0))
DISNEY_FIELDS = {"spec_trans": "transmission"}
SAMPLING_RATES = ("main_specular_sampling_rate", "clearcoat_sampling_rate", "diffuse_reflectance_sampling_rate",
                  "specular_reflectance_sampling_rate", "specular_transmittance_sampling_rate",
                  "diffuse_transmittance_sampling_rate")
# Mitsuba's masking is Smith's separable form for both distributions.
MICROFACET = {"ggx": "ggx_separable", "beckmann": "beckmann"}
SMOOTH = {"roughness": 0.0, "microfacet": "ggx"}  # the lobe fields of a smooth BSDF


def bsdf_spec(builder, bsdf: Plugin) -> MaterialSpec:
    """The material spec of a BSDF plugin (its name is the builder's to give)."""
    t = bsdf.type
    if t == "twosided":
        nested = bsdf.objects("bsdf")
        if len(nested) > 1:
            warn(nested[1], "twosided with a second BSDF for the back face: the first shades both sides")
        return _two_sided(_inner(builder, bsdf))
    if t == "mask":
        return _mask(builder, bsdf)
    if t in ("bumpmap", "normalmap"):
        return mapped_spec(builder, bsdf, _inner(builder, bsdf))
    if t == "blendbsdf":
        blended = blended_diffuse(builder, bsdf)  # two diffuse colours: exactly one diffuse BSDF
        if blended is not None:
            return blended
        return _blend(builder, bsdf)
    if t == "diffuse":
        colour, texture = builder.base_colour(bsdf, "reflectance", DEFAULT_REFLECTANCE)
        return MaterialSpec("", "diffuse", base_color=colour, base_color_texture=texture, sidedness="back_black")
    if t in ("conductor", "roughconductor"):
        return _conductor(builder, bsdf)
    if t in ("dielectric", "roughdielectric", "thindielectric"):
        lobe = _roughness(builder, bsdf) if t == "roughdielectric" else SMOOTH
        tint, tint_texture = _tint(builder, bsdf, "specular_transmittance", (1.0,) * 3)
        reflect, reflect_texture = _tint(builder, bsdf, "specular_reflectance", (1.0,) * 3)
        return MaterialSpec("", "dielectric", base_color=tint, base_color_texture=tint_texture, specular_color=reflect,
                            parameter_textures=() if reflect_texture is None else (("specular_color", reflect_texture),),
                            ior=_relative_ior(bsdf, DEFAULT_GLASS_IOR), **lobe,
                            thin=t == "thindielectric")
    if t in ("plastic", "roughplastic"):
        return _plastic(builder, bsdf)
    if t in ("principled", "principledthin"):
        return _principled(builder, bsdf)
    if t == "null":
        return MaterialSpec("", "null")
    warn(bsdf, "this BSDF type is not supported yet: rendered as Mitsuba's default diffuse")
    return MaterialSpec("", "diffuse", base_color=DEFAULT_REFLECTANCE, sidedness="back_black")


def _two_sided(spec: MaterialSpec) -> MaterialSpec:
    """Mitsuba's twosided around a BSDF: the back shades as the front (a mix: both of its own)."""
    if spec.mix is not None:
        return replace(spec, mix=tuple(_two_sided(part) for part in spec.mix))
    return replace(spec, sidedness="two_sided", front_both_sides=spec.kind == "disney")


def _blend(builder, bsdf: Plugin) -> MaterialSpec:
    """Mitsuba's blendbsdf: a mix of its two BSDFs, the second with probability `weight` (a number
    or a texture's first channel) at each shading point."""
    nested = bsdf.objects("bsdf")
    if len(nested) != 2:
        raise bsdf.error(f"needs two nested BSDFs, not {len(nested)}")
    parts = tuple(bsdf_spec(builder, builder.visit(b)) for b in nested)
    if _mix_depth(parts[0]) >= MAX_MIX_DEPTH or _mix_depth(parts[1]) >= MAX_MIX_DEPTH:
        raise bsdf.error(f"blendbsdf nested more than {MAX_MIX_DEPTH} deep")
    for part, plugin in zip(parts, nested):
        if part.opacity < 1.0 or part.opacity_texture is not None:
            warn(plugin, "a mask inside a blendbsdf is left out (wrap the blendbsdf in the mask)")
    weight = bsdf.properties.get("weight")
    textures = ()
    if isinstance(weight, Plugin) and weight.kind == "texture" and weight.type in ("bitmap", "checkerboard"):
        bsdf.used.add("weight")
        w, textures = 1.0, (("mix_weight", float_texture(builder, weight)),)
    else:
        w = builder.scalar(bsdf, "weight", 0.5)
        if not 0.0 <= w <= 1.0:
            raise bsdf.error(f"weight {w:g} is not between 0 and 1")
    return MaterialSpec("", parts[0].kind, mix=parts, mix_weight=w, parameter_textures=textures)


def _mix_depth(spec: MaterialSpec) -> int:
    return 0 if spec.mix is None else 1 + max(_mix_depth(part) for part in spec.mix)


def _index_part(builder, bsdf: Plugin, name: str, default) -> tuple:
    """A conductor's eta or k: (a colour, None) or ((1, 1, 1), a bitmap or checkerboard texture whose
    values are the index itself, unbounded as Mitsuba reads them)."""
    value = bsdf.properties.get(name)
    if isinstance(value, Plugin) and value.kind == "texture" and value.type in ("bitmap", "checkerboard"):
        bsdf.used.add(name)
        return (1.0, 1.0, 1.0), builder.texture(builder.visit(value))
    return builder.colour(bsdf, name, default, bounded=False), None


def _tint(builder, bsdf: Plugin, name: str, default) -> tuple:
    """A specular tint: (colour, None) or ((1, 1, 1), a bitmap or checkerboard texture); a mesh
    attribute there is a warning (only diffuse colours take them)."""
    value = bsdf.properties.get(name)
    if isinstance(value, Plugin) and value.kind == "texture" and value.type in ("bitmap", "checkerboard"):
        bsdf.used.add(name)
        return (1.0, 1.0, 1.0), builder.texture(builder.visit(value))
    if isinstance(value, Plugin) and value.kind == "texture" and value.type == "mesh_attribute":
        bsdf.used.add(name)
        warn(bsdf, f"a mesh_attribute on '{name}' is not supported: white is used")
        return tuple(default), None
    return builder.colour(bsdf, name, default), None


def _inner(builder, bsdf: Plugin) -> MaterialSpec:
    nested = bsdf.objects("bsdf")
    if not nested:
        raise bsdf.error("needs a nested <bsdf>")
    return bsdf_spec(builder, builder.visit(nested[0]))


def _mask(builder, bsdf: Plugin) -> MaterialSpec:
    """Mitsuba's mask: the nested BSDF where the surface is, with probability `opacity`."""
    inner = _inner(builder, bsdf)
    value = bsdf.properties.get("opacity")
    if isinstance(value, Plugin) and value.kind == "texture" and value.type in ("bitmap", "checkerboard"):
        bsdf.used.add("opacity")
        return replace(inner, opacity=1.0, opacity_texture=float_texture(builder, value))
    opacity = builder.scalar(bsdf, "opacity", 0.5)
    if not 0.0 <= opacity <= 1.0:
        raise bsdf.error(f"opacity {opacity:g} is not between 0 and 1")
    return replace(inner, opacity=opacity)


def _conductor(builder, bsdf: Plugin) -> MaterialSpec:
    """Mitsuba's conductor and roughconductor: a named metal, eta and k, or a perfect mirror (`none`),
    the Fresnel tinted by specular_reflectance (a colour or a texture)."""
    tint, tint_texture = _tint(builder, bsdf, "specular_reflectance", (1.0, 1.0, 1.0))
    common = {**(_roughness(builder, bsdf) if bsdf.type == "roughconductor" else SMOOTH), "sidedness": "back_black",
              "specular_color": tint}
    if tint_texture is not None:
        common["parameter_textures"] = (*common.get("parameter_textures", ()), ("specular_color", tint_texture))
    if bsdf.has("eta") or bsdf.has("k"):
        (eta, eta_texture), (k, k_texture) = (_index_part(builder, bsdf, "eta", (0.0, 0.0, 0.0)),
                                              _index_part(builder, bsdf, "k", (1.0, 1.0, 1.0)))
        textures = tuple((role, t) for role, t in (("eta", eta_texture), ("k", k_texture)) if t is not None)
        common["parameter_textures"] = (*common.get("parameter_textures", ()), *textures)
        spec = MaterialSpec("", "conductor", eta=eta, k=k, **common)
    else:
        name = bsdf.text("material", "none")
        if name == "none":  # Mitsuba's perfect mirror: a Fresnel of 1 (Schlick from 1), times the tint
            return MaterialSpec("", "conductor", base_color=(1.0, 1.0, 1.0), **common)
        known = {m.lower(): m for m in metal_names()}
        if name.lower() not in known:
            raise bsdf.error(f"unknown conductor material '{name}' (known: {', '.join(sorted(known.values()))})")
        spec = MaterialSpec("", "conductor", metal=known[name.lower()], **common)
    return spec


def _plastic(builder, bsdf: Plugin) -> MaterialSpec:
    """Mitsuba's plastic and roughplastic: Lantern's `plastic` kind is their model."""
    lobe = _roughness(builder, bsdf) if bsdf.type == "roughplastic" else SMOOTH
    if lobe.get("roughness_v") is not None:  # as Mitsuba, whose roughplastic refuses anisotropic roughness
        raise bsdf.error("roughplastic takes one alpha, not alpha_u and alpha_v that differ")
    if "alpha_texture" in lobe:
        raise bsdf.error("a textured alpha on roughplastic is not supported (its coating's tables need one alpha)")
    eta = _relative_ior(bsdf, DEFAULT_PLASTIC_IOR)
    if eta == 1.0:
        raise bsdf.error("int_ior and ext_ior are equal: the coating would not be there")
    colour, texture = builder.base_colour(bsdf, "diffuse_reflectance", DEFAULT_REFLECTANCE)
    specular, tint_texture = _tint(builder, bsdf, "specular_reflectance", (1.0, 1.0, 1.0))
    specular_texture = () if tint_texture is None else (("specular_color", tint_texture),)
    return MaterialSpec("", "plastic", base_color=colour, base_color_texture=texture, roughness=lobe["roughness"],
                        microfacet=lobe["microfacet"], ior=eta, nonlinear=bool(bsdf.get("nonlinear", False)),
                        specular_color=specular, parameter_textures=specular_texture,
                        sidedness="back_black")


def _roughness(builder, bsdf: Plugin) -> dict:
    """The MaterialSpec fields of a rough BSDF's microfacet lobe: Lantern's perceptual roughness
    (alpha = roughness^2) from Mitsuba's alpha (alpha_u), the microfacet model, the roughness along
    v where alpha_v differs, and for textured widths the textures (the constant roughness then only
    marks the lobe rough)."""
    distribution = bsdf.text("distribution", "beckmann").lower()
    if distribution not in MICROFACET:
        raise bsdf.error(f"distribution '{distribution}' (beckmann or ggx)")
    if not bsdf.get("sample_visible", True):
        warn(bsdf, "sample_visible = false: Lantern draws normals its own way (the image is the same)")
    anisotropic = bsdf.has("alpha_u") or bsdf.has("alpha_v")
    alpha = _width(builder, bsdf, "alpha_u" if anisotropic else "alpha")
    alpha_v = _width(builder, bsdf, "alpha_v") if anisotropic else alpha
    fields = {"microfacet": MICROFACET[distribution]}
    if isinstance(alpha, float) and isinstance(alpha_v, float):
        return {**fields, "roughness": min(1.0, math.sqrt(alpha)),
                "roughness_v": None if alpha_v == alpha else min(1.0, math.sqrt(alpha_v))}
    as_texture = [w if not isinstance(w, float) else TextureSpec.constant(w) for w in (alpha, alpha_v)]
    return {**fields, "roughness": 0.5, "alpha_texture": as_texture[0],
            "alpha_v_texture": as_texture[1] if anisotropic else None}


def _width(builder, bsdf: Plugin, name: str):
    """Mitsuba's alpha parameter `name`: a number, or a texture (its TextureSpec)."""
    value = bsdf.properties.get(name)
    if isinstance(value, Plugin) and value.kind == "texture" and value.type in ("bitmap", "checkerboard"):
        bsdf.used.add(name)
        return float_texture(builder, value)
    alpha = builder.scalar(bsdf, name, 0.1)
    if alpha < 0:
        raise bsdf.error(f"{name} {alpha:g} is negative")
    return alpha


def float_texture(builder, texture: Plugin) -> TextureSpec:
    """A texture read as a number (its first channel), as Mitsuba evaluates it for a scalar
    parameter: Mitsuba 3's checkerboard then puts color0 where its colour evaluation puts color1
    (its eval_1 tests the other parity), which its scenes' images show, so the colours swap here."""
    spec = builder.texture(builder.visit(texture))
    if spec.kind == "checkerboard":
        spec = replace(spec, color0=spec.color1, color1=spec.color0)
    return spec


def _relative_ior(bsdf: Plugin, default_int: float) -> float:
    return _ior_value(bsdf, "int_ior", default_int) / _ior_value(bsdf, "ext_ior", IOR_NAMES["air"])


def _ior_value(bsdf: Plugin, name: str, default: float) -> float:
    value = bsdf.get(name, default)
    if isinstance(value, str):
        if value.lower() not in IOR_NAMES:
            raise bsdf.error(f"unknown {name} '{value}' (known: {', '.join(IOR_NAMES)})")
        return IOR_NAMES[value.lower()]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value <= 0:
        raise bsdf.error(f"{name} must be a positive number or a known name")
    return float(value)


def _principled(builder, bsdf: Plugin) -> MaterialSpec:
    """Mitsuba's principled and principledthin: Lantern's `disney` kind is their model, every
    scalar parameter a number or a texture (its first channel)."""
    thin = bsdf.type == "principledthin"
    colour, texture = builder.base_colour(bsdf, "base_color", DEFAULT_REFLECTANCE)
    fields, textures = {}, []
    for name, default in (PRINCIPLEDTHIN_PARAMS if thin else PRINCIPLED_PARAMS):
        value = bsdf.properties.get(name)
        field = DISNEY_FIELDS.get(name, name)
        if isinstance(value, Plugin) and value.kind == "texture" and value.type in ("bitmap", "checkerboard"):
            bsdf.used.add(name)
            fields[field] = 1.0  # the texture's value multiplies 1
            textures.append((field, float_texture(builder, value)))
        else:
            fields[field] = builder.scalar(bsdf, name, default)
    rates = [name for name in SAMPLING_RATES if bsdf.has(name)]
    if rates:
        bsdf.used.update(rates)
        if any(builder.scalar(bsdf, name, 1.0) != 1.0 for name in rates):
            warn(bsdf, f"{', '.join(rates)}: Lantern draws the lobes at Mitsuba's default rates (only the noise "
                       "differs)")
    return MaterialSpec("", "disney", base_color=colour, base_color_texture=texture, **fields,
                        ior=_principled_eta(builder, bsdf, thin), thin=thin, parameter_textures=tuple(textures),
                        sidedness="two_sided")  # the model itself shades the back side


def _principled_eta(builder, bsdf: Plugin, thin: bool) -> float:
    """The index: principledthin's `eta`; principled's `eta`, or Disney's `specular` made an index
    as Mitsuba makes it (never both), kept above 1 where the surface transmits."""
    if thin:
        return builder.scalar(bsdf, "eta", 1.5)
    transmits = _flag(bsdf, "spec_trans")
    if bsdf.has("eta"):
        if bsdf.has("specular"):
            raise bsdf.error("give eta or specular, not both (each sets the index)")
        eta = builder.scalar(bsdf, "eta", 1.5)
        if eta <= 0.0:
            raise bsdf.error(f"eta {eta:g} is not positive")
        return 1.001 if transmits and eta == 1.0 else eta
    specular = builder.scalar(bsdf, "specular", 0.5)
    if not 0.0 <= specular < 12.5:
        raise bsdf.error(f"specular {specular:g} is outside [0, 12.5), where it gives an index")
    if transmits and specular == 0.0:
        specular = 1e-3
    return 2.0 / (1.0 - math.sqrt(0.08 * specular)) - 1.0


def _flag(bsdf: Plugin, name: str) -> bool:
    """Mitsuba's get_flag: the parameter is given and is not the number 0."""
    value = bsdf.properties.get(name)
    return value is not None and not (isinstance(value, (int, float)) and not isinstance(value, bool) and value == 0)

"""Mitsuba 3's normalmap and bumpmap BSDFs: the BSDF inside, shaded with its normal tilted by a
texture (the spec's normal_map, or bump_map with bump_scale; renderer/materials/mapped_frames.py
draws them as Mitsuba does, its shadow-terminator term included).

normalmap's `normalmap` texture and bumpmap's one nested texture may be a bitmap (read raw where
`raw` is set, as Mitsuba reads it), a checkerboard, or a `rawconstant` (one value everywhere).
"""
from __future__ import annotations

from dataclasses import replace

from renderer.scene.description import MaterialSpec, TextureSpec
from renderer.scene.mitsuba.plugins import Plugin, Rgb
from renderer.scene.mitsuba.scene_warnings import warn

# Mitsuba's switches with their defaults; Lantern always draws the default.
ALWAYS_ON = ("flip_invalid_normals", "use_shadowing_function")


def mapped_spec(builder, bsdf: Plugin, inner: MaterialSpec) -> MaterialSpec:
    """The spec of a normalmap or bumpmap plugin around the spec `inner` of its nested BSDF."""
    for name in ALWAYS_ON:
        if not bsdf.get(name, True):
            warn(bsdf, f"{name} = false is not supported: drawn as true, Mitsuba's default")
    if inner.normal_map is not None or inner.bump_map is not None:
        warn(bsdf, f"a {bsdf.type} around another normal or bump map: only the outer {bsdf.type} is used")
        inner = replace(inner, normal_map=None, bump_map=None, bump_scale=1.0)
    if bsdf.type == "normalmap":
        texture = bsdf.properties.get("normalmap")
        if not isinstance(texture, Plugin) or texture.kind != "texture":
            raise bsdf.error("needs a <texture name=\"normalmap\">")
        bsdf.used.add("normalmap")
        map_texture = _texture(builder, bsdf, texture)
        return inner if map_texture is None else replace(inner, normal_map=map_texture)
    textures = bsdf.objects("texture")
    if len(textures) != 1:
        raise bsdf.error(f"needs exactly one nested <texture> (the height), not {len(textures)}")
    map_texture = _texture(builder, bsdf, textures[0])
    if map_texture is None:
        return inner
    return replace(inner, bump_map=map_texture, bump_scale=bsdf.number("scale", 1.0))


def _texture(builder, bsdf: Plugin, texture: Plugin) -> TextureSpec | None:
    """The map's texture, or None (with a warning) for a texture type Lantern does not read."""
    builder.visit(texture)
    if texture.type in ("bitmap", "checkerboard"):
        return builder.texture(texture)
    if texture.type == "rawconstant":
        value = _constant(texture)
        return TextureSpec("checkerboard", nearest=True, color0=value, color1=value)  # one value everywhere
    warn(bsdf, f"a <texture type=\"{texture.type}\"> as its map is not supported yet: the BSDF inside is "
               "used as it is")
    return None


def _constant(texture: Plugin) -> tuple[float, float, float]:
    value = texture.get("value", 1.0)
    if isinstance(value, Rgb):
        return value.value
    if isinstance(value, tuple) and len(value) == 3:
        return tuple(float(v) for v in value)
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return (float(value),) * 3
    raise texture.error("'value' must be a number, <vector> or <rgb>")

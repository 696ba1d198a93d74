"""A resolved Mitsuba scene tree (xml_document.py) read into plugins: each object tag with its type,
id, typed properties and nested objects, `<ref>`s replaced by the object they name, transforms
composed into 4x4 matrices.

This is Mitsuba's scene language only; what each plugin means for Lantern is scene_builder.py's.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Union

import numpy as np

from renderer.scene.errors import SceneError
from renderer.scene.mitsuba.xml_document import Element, Resolution

# Tags that make an object (a plugin) and tags that give one a property.
OBJECT_TAGS = frozenset(("scene", "shape", "bsdf", "emitter", "sensor", "film", "rfilter", "sampler",
                         "integrator", "medium", "phase", "texture", "volume"))
VALUE_TAGS = frozenset(("integer", "float", "boolean", "string", "point", "vector", "rgb", "color",
                        "spectrum", "transform"))
TRANSFORM_STEPS = frozenset(("translate", "rotate", "scale", "matrix", "lookat"))
NUMBER = re.compile(r"[,\s]+")


@dataclass(frozen=True)
class Rgb:
    """An `<rgb>` value: linear Rec.709."""
    value: tuple[float, float, float]


@dataclass(frozen=True)
class Spectrum:
    """A `<spectrum>` value: one number (a uniform spectrum) or (wavelength nm, value) samples,
    written inline or read from a file. Made RGB where it is used (scene_builder.py), since Mitsuba
    converts reflectances and emission differently."""
    wavelengths: tuple[float, ...] = ()
    values: tuple[float, ...] = ()
    uniform: float | None = None


Value = Union[int, float, bool, str, tuple, Rgb, Spectrum, np.ndarray, "Plugin"]


@dataclass
class Plugin:
    kind: str  # the tag: shape, bsdf, emitter, ...
    type: str  # the plugin's name: obj, diffuse, area, ...
    file: Path
    line: int
    id: str | None = None
    properties: dict[str, Value] = field(default_factory=dict)
    children: list["Plugin"] = field(default_factory=list)  # nested objects without a name
    # Which properties and children the scene builder used: the rest get one warning each.
    used: set = field(default_factory=set)

    def where(self) -> str:
        return f"{self.file}: line {self.line}"

    def label(self) -> str:
        return f"<{self.kind} type=\"{self.type}\">"

    def error(self, message: str) -> SceneError:
        return SceneError(self.file, f"line {self.line}: {self.label()}: {message}")

    def get(self, name: str, default=None):
        self.used.add(name)
        return self.properties.get(name, default)

    def has(self, name: str) -> bool:
        return name in self.properties

    def number(self, name: str, default: float) -> float:
        value = self.get(name, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(f"'{name}' must be a number")
        return float(value)

    def integer(self, name: str, default: int) -> int:
        value = self.get(name, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(f"'{name}' must be an <integer>")
        return value

    def text(self, name: str, default: str | None = None) -> str | None:
        value = self.get(name, default)
        if value is not None and not isinstance(value, str):
            raise self.error(f"'{name}' must be a <string>")
        return value

    def transform(self, name: str = "to_world") -> np.ndarray:
        value = self.get(name, None)
        if value is None:
            return np.eye(4)
        if not isinstance(value, np.ndarray):
            raise self.error(f"'{name}' must be a <transform>")
        return value

    def objects(self, kind: str) -> list["Plugin"]:
        """Nested objects of a kind, named or not, in file order."""
        named = [(n, v) for n, v in self.properties.items() if isinstance(v, Plugin) and v.kind == kind]
        for name, _ in named:
            self.used.add(name)
        return [v for _, v in named] + [c for c in self.children if c.kind == kind]


def read_plugins(root: Element, resolution: Resolution) -> Plugin:
    """The scene plugin of a resolved document."""
    return _Reader(resolution).object(root, {})


class _Reader:
    def __init__(self, resolution: Resolution):
        self.resolution = resolution
        self.ids: dict[str, Plugin] = {}

    def object(self, element: Element, attrs: dict) -> Plugin:
        kind = element.tag
        type_ = element.attrs.get("type", "scene" if kind == "scene" else None)
        if type_ is None:
            raise element.error(f"<{kind}> needs a type=\"...\" attribute")
        plugin = Plugin(kind, type_, element.file, element.line, element.attrs.get("id"))
        for child in element.children:
            name = child.attrs.get("name")
            if child.tag in OBJECT_TAGS or (child.tag == "spectrum" and "type" in child.attrs):
                nested = self.object(child, child.attrs)
                if name:
                    plugin.properties[name] = nested
                else:
                    plugin.children.append(nested)
            elif child.tag == "ref":
                target = self.reference(child)
                if name:
                    plugin.properties[name] = target
                else:
                    plugin.children.append(target)
            elif child.tag in VALUE_TAGS:
                if not name:
                    raise child.error(f"<{child.tag}> needs a name=\"...\" attribute")
                plugin.properties[name] = self.value(child)
            else:
                raise child.error(f"unknown element <{child.tag}>")
        if plugin.id is not None:
            if plugin.id in self.ids:
                raise element.error(f"id \"{plugin.id}\" is used twice (first at line {self.ids[plugin.id].line})")
            self.ids[plugin.id] = plugin
        return plugin

    def reference(self, element: Element) -> Plugin:
        target = element.attrs.get("id")
        if target is None:
            raise element.error("<ref> needs an id=\"...\" attribute")
        if target not in self.ids:
            raise element.error(f"<ref id=\"{target}\">: no object with that id comes before it")
        return self.ids[target]

    def value(self, element: Element):
        tag, attrs = element.tag, element.attrs
        if tag == "transform":
            return self.transform(element)
        if tag == "string":
            return _attr(element, "value")
        if tag == "boolean":
            text = _attr(element, "value").strip().lower()
            if text not in ("true", "false"):
                raise element.error(f"<boolean> value '{text}' is neither true nor false")
            return text == "true"
        if tag == "integer":
            text = _attr(element, "value")
            try:
                return int(text)
            except ValueError:
                raise element.error(f"<integer> value '{text}' is not a whole number") from None
        if tag == "float":
            return _numbers(element, _attr(element, "value"), 1)[0]
        if tag in ("point", "vector"):
            if "value" in attrs:
                return tuple(_numbers(element, attrs["value"], 3))
            return tuple(_number(element, attrs.get(axis, "0")) for axis in "xyz")
        if tag in ("rgb", "color"):
            values = _numbers(element, _attr(element, "value"))
            if len(values) == 1:
                values = values * 3
            if len(values) != 3:
                raise element.error(f"<{tag}> needs 1 or 3 numbers, not {len(values)}")
            return Rgb(tuple(values))
        return self.spectrum(element)

    def spectrum(self, element: Element) -> Spectrum:
        attrs = element.attrs
        if "filename" in attrs:
            path = self.resolution.find(attrs["filename"], element.file)
            if not path.exists():
                raise element.error(f"<spectrum> file {attrs['filename']} not found")
            self.resolution.read.append(path)
            pairs = []
            for line in path.read_text(errors="replace").splitlines():
                fields = line.split("#", 1)[0].split()
                if fields:
                    pairs.append(fields[:2])
            return _pairs(element, pairs, path.name)
        text = _attr(element, "value")
        if ":" not in text:
            values = _numbers(element, text)
            if len(values) != 1:
                raise element.error("<spectrum> value is one number or wavelength:value pairs")
            return Spectrum(uniform=values[0])
        pairs = [item.split(":") for item in re.split(r"[,\s]+", text.strip()) if item]
        return _pairs(element, pairs, "value")

    def transform(self, element: Element) -> np.ndarray:
        matrix = np.eye(4)
        for step in element.children:
            if step.tag not in TRANSFORM_STEPS:
                raise step.error(f"unknown transform step <{step.tag}> (translate, rotate, scale, matrix, lookat)")
            matrix = _step(step) @ matrix  # each step applies after the ones before it
        return matrix


def _attr(element: Element, name: str) -> str:
    if name not in element.attrs:
        raise element.error(f"<{element.tag}> needs a {name}=\"...\" attribute")
    return element.attrs[name]


def _number(element: Element, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise element.error(f"'{text}' is not a number") from None
    if not math.isfinite(value):
        raise element.error(f"'{text}' is not a finite number")
    return value


def _numbers(element: Element, text: str, count: int | None = None) -> list[float]:
    values = [_number(element, part) for part in NUMBER.split(text.strip()) if part]
    if count is not None and len(values) != count:
        raise element.error(f"<{element.tag}> needs {count} number{'s' if count > 1 else ''}, not {len(values)}")
    return values


def _pairs(element: Element, pairs, source: str) -> Spectrum:
    try:
        data = [(float(w), float(v)) for w, v in pairs]
    except ValueError:
        raise element.error(f"<spectrum> {source}: wavelength:value pairs expected") from None
    if len(data) < 2 or any(b[0] <= a[0] for a, b in zip(data, data[1:])):
        raise element.error(f"<spectrum> {source}: at least two pairs, with increasing wavelengths")
    return Spectrum(tuple(w for w, _ in data), tuple(v for _, v in data))


def _vector(element: Element, name: str) -> np.ndarray:
    return np.array(_numbers(element, _attr(element, name), 3))


def _step(step: Element) -> np.ndarray:
    attrs = step.attrs
    m = np.eye(4)
    if step.tag == "translate":
        m[:3, 3] = (_numbers(step, attrs["value"], 3) if "value" in attrs
                    else [_number(step, attrs.get(a, "0")) for a in "xyz"])
    elif step.tag == "scale":
        if "value" in attrs:
            values = _numbers(step, attrs["value"])
            if len(values) not in (1, 3):
                raise step.error("<scale> value is one number or three")
            m[:3, :3] = np.diag(values * 3 if len(values) == 1 else values)
        else:
            m[:3, :3] = np.diag([_number(step, attrs.get(a, "1")) for a in "xyz"])
    elif step.tag == "rotate":
        axis = (np.array(_numbers(step, attrs["value"], 3)) if "value" in attrs
                else np.array([_number(step, attrs.get(a, "0")) for a in "xyz"]))
        norm = np.linalg.norm(axis)
        if norm == 0:
            raise step.error("<rotate> needs a non-zero axis")
        m[:3, :3] = _rotation(axis / norm, math.radians(_number(step, _attr(step, "angle"))))
    elif step.tag == "matrix":
        values = _numbers(step, _attr(step, "value"))
        if len(values) == 16:
            m = np.array(values).reshape(4, 4)
        elif len(values) == 9:
            m[:3, :3] = np.array(values).reshape(3, 3)
        else:
            raise step.error(f"<matrix> needs 16 or 9 numbers, not {len(values)}")
    else:
        origin, target = _vector(step, "origin"), _vector(step, "target")
        up = _vector(step, "up") if "up" in attrs else np.array([0.0, 1.0, 0.0])
        m = _look_at(step, origin, target, up)
    return m


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Right-handed rotation by `angle` radians about a unit axis (Rodrigues)."""
    x, y, z = axis
    c, s = math.cos(angle), math.sin(angle)
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return c * np.eye(3) + s * k + (1.0 - c) * np.outer(axis, axis)


def _look_at(step: Element, origin, target, up) -> np.ndarray:
    """Mitsuba's look_at: columns (left, up, forward, origin); the camera looks down its local +z."""
    forward = target - origin
    if np.linalg.norm(forward) == 0:
        raise step.error("<lookat> origin and target are the same point")
    forward = forward / np.linalg.norm(forward)
    left = np.cross(up, forward)
    if np.linalg.norm(left) < 1e-12:
        raise step.error("<lookat> up is parallel to the view direction")
    left = left / np.linalg.norm(left)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = left, np.cross(forward, left), forward, origin
    return m

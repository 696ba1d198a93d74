"""The vocabulary the scene format is written in: fields, sections, rules, object kinds, ranges.

The format itself (which sections and fields there are, their defaults and ranges) is the tables
of schema.py; this module holds only the types those tables are made of and the small values
every table uses (REQUIRED, the common ranges, the value kinds the loader converts).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional


class _Required:
    """Marker default for fields that must be written in the file."""

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED = _Required()

# Key of the set of written field names in the values a section's Rule checks (see Rule).
WRITTEN = "<written>"

# Value kinds a field can have. The loader converts raw TOML values according to these.
VALUE_KINDS = {
    "bool": "true or false",
    "string": "string",
    "int": "integer",
    "float": "float",
    "vec3": "array of 3 floats",
    "dir3": "array of 3 floats",  # a direction: non-zero, normalised by the loader
    "int3": "array of 3 integers",
    "int4": "array of 4 integers",
    "vec2": "array of 2 floats",
    "points2": "array of [float, float] pairs",
    "scale": "float, or array of 3 equal floats",
    "scale3": "float, or array of 3 floats",
    "table": "table",
    "tables": "array of tables",
}


def format_number(x: float) -> str:
    """Numbers as a person would write them: 1 rather than 1.0 in ranges and messages."""
    if isinstance(x, float) and x.is_integer() and abs(x) < 1e15:
        return str(int(x))
    return repr(x)


@dataclass(frozen=True)
class Range:
    """A numeric interval (bounds may be open or absent) plus isolated extra values."""

    lo: Optional[float] = None
    hi: Optional[float] = None
    lo_open: bool = False
    hi_open: bool = False
    also: tuple[float, ...] = ()  # e.g. -1 for render.max_depth

    def __contains__(self, x: float) -> bool:
        if x in self.also:
            return True
        if self.lo is not None and (x < self.lo or (self.lo_open and x == self.lo)):
            return False
        if self.hi is not None and (x > self.hi or (self.hi_open and x == self.hi)):
            return False
        return True

    def __str__(self) -> str:
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            opening, closing = "(" if self.lo_open else "[", ")" if self.hi_open else "]"
            text = f"{opening}{format_number(lo)}, {format_number(hi)}{closing}"
        elif lo is not None:
            text = f"{'>' if self.lo_open else '>='} {format_number(lo)}"
        elif hi is not None:
            text = f"{'<' if self.hi_open else '<='} {format_number(hi)}"
        else:
            text = "any"
        extras = " or ".join(format_number(a) for a in self.also)
        return f"{extras} or {text}" if extras else text


POSITIVE = Range(0.0, lo_open=True)
NON_NEGATIVE = Range(0.0)
UNIT = Range(0.0, 1.0)
AT_LEAST_ONE = Range(1)
# An exposure in EV scales by 2^EV in float32: beyond this the scale is 0 or infinite (app.py's
# --exposure checks the same bounds before it imports anything of the renderer).
EXPOSURE_EV = Range(-126.0, 127.0)


@dataclass(frozen=True)
class Field:
    name: str
    kind: str  # a key of VALUE_KINDS
    default: object
    description: str
    range: Optional[Range] = None  # applies to each component of a vector
    choices: Optional[tuple[str, ...]] = None
    only_for: Optional[tuple[str, ...]] = None  # the section `type`s this field belongs to
    attr: Optional[str] = None  # model attribute when it differs from `name`
    in_model: bool = True  # False: no model attribute of its own (e.g. emission_strength)
    default_doc: Optional[str] = None  # shown instead of the default when it is computed
    allowed_doc: Optional[str] = None  # shown instead of the range when another check applies
    geometries: Optional[tuple[str, ...]] = None  # the scene geometry kinds it belongs to (None: all)
    items: Optional[tuple["Field", ...]] = None  # kind "tables": the fields of each table
    # (type, default) pairs of the section `type`s with a default of their own (e.g. a smooth
    # conductor); the other types take `default`.
    type_defaults: tuple[tuple[str, object], ...] = ()

    @property
    def model_attr(self) -> str:
        return self.attr or self.name

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def applies_to(self, kind: Optional[str]) -> bool:
        return self.only_for is None or kind in self.only_for

    def default_for(self, kind: Optional[str]) -> object:
        """The default in a table of the given `type`."""
        return dict(self.type_defaults).get(kind, self.default)

    def in_geometry(self, geometry: str) -> bool:
        return self.geometries is None or geometry in self.geometries


@dataclass(frozen=True)
class Rule:
    """A constraint between fields. `check` gets the converted values (defaults filled in)
    and returns a problem description, or None when the values are fine. In a section's rules the
    values also hold, under WRITTEN, the names of the fields the file wrote (a default and the
    same value written out are not the same thing when fields exclude each other)."""

    text: str
    check: Callable[[dict], Optional[str]]


@dataclass(frozen=True)
class Section:
    name: str  # as written in the file, e.g. "render.march" or "materials.<name>"
    description: str
    fields: tuple[Field, ...]
    rules: tuple[Rule, ...] = ()
    heading: Optional[str] = None  # markdown heading, when the name alone is ambiguous

    def field(self, name: str) -> Field:
        return next(f for f in self.fields if f.name == name)

    def allowed(self, kind: Optional[str] = None) -> tuple[str, ...]:
        """Names of the fields a table of this section (of the given `type`) may contain."""
        return tuple(f.name for f in self.fields if f.applies_to(kind))


@dataclass(frozen=True)
class NodeKind:
    """An SDF primitive (no children) or operator (children)."""

    name: str
    description: str
    params: tuple[Field, ...] = ()
    rules: tuple[Rule, ...] = ()
    min_children: int = 0
    max_children: Optional[int] = 0  # None: no upper limit

    @property
    def is_operator(self) -> bool:
        return self.max_children != 0

    def children_text(self) -> str:
        if self.max_children == self.min_children:
            return f"exactly {self.min_children} child" + ("" if self.min_children == 1 else "ren")
        return f"at least {self.min_children} children"


@dataclass(frozen=True)
class MeshKind:
    """A `type` of object in a `mesh` scene: a model file, an analytic shape or a generated mesh."""

    name: str
    description: str
    params: tuple[Field, ...] = ()
    needs_material: bool = True  # False: the object may bring its own materials (model files)
    uniform_scale_reason: Optional[str] = None  # set when only a uniform scale keeps the shape
    rules: tuple[Rule, ...] = ()


@dataclass(frozen=True)
class Generator:
    """A procedural mesh of a `generated` object; its parameters are fields of that object."""

    name: str
    description: str
    params: tuple[Field, ...] = ()
    rules: tuple["Rule", ...] = ()

"""pbrt-v4's typed parameter lists ("float fov" [45], "rgb L" [1 1 1], "texture reflectance" "wood",
...): read after a directive while the next token is a quoted string. Each parameter remembers
whether the scene's mapping read it, so those nothing read become one warning each."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from renderer.scene.errors import SceneError
from renderer.scene.pbrt.tokenizer import Token, TokenStream, find

NUMERIC = {"float": 1, "integer": 1, "point2": 2, "vector2": 2, "point3": 3, "vector3": 3, "normal3": 3,
           "normal": 3, "point": 3, "vector": 3, "rgb": 3, "color": 3, "blackbody": 1}
TEXTUAL = ("string", "texture", "bool")
TYPES = tuple(NUMERIC) + TEXTUAL + ("spectrum",)


@dataclass
class Param:
    type: str
    name: str
    values: list  # numbers, or strings (bools as True / False)
    token: Token  # the declaration, for messages
    used: bool = False

    @property
    def label(self) -> str:
        return f"'{self.type} {self.name}'"

    def error(self, message: str) -> SceneError:
        return self.token.error(f"{self.label}: {message}")


@dataclass
class ParamList:
    """The parameters of one directive, found by name."""

    params: list[Param] = field(default_factory=list)

    def find(self, name: str, types: tuple[str, ...] | None = None) -> Param | None:
        for p in self.params:
            if p.name == name and (types is None or p.type in types):
                p.used = True
                return p
        return None

    def has(self, name: str) -> bool:
        return any(p.name == name for p in self.params)

    def _one(self, name, types, default, kind):
        p = self.find(name, types)
        if p is None:
            return default
        if len(p.values) != 1 or not isinstance(p.values[0], kind) or isinstance(p.values[0], bool) != (kind is bool):
            raise p.error(f"expected one {types[0]} value")
        return p.values[0]

    def float(self, name: str, default: float | None = None) -> float | None:
        value = self._one(name, ("float", "integer"), default, (int, float))
        return None if value is None else float(value)

    def integer(self, name: str, default: int | None = None) -> int | None:
        p = self.find(name, ("integer",))
        if p is None:
            return default
        if len(p.values) != 1 or float(p.values[0]) != int(p.values[0]):
            raise p.error("expected one integer")
        return int(p.values[0])

    def boolean(self, name: str, default: bool) -> bool:
        return self._one(name, ("bool",), default, bool)

    def string(self, name: str, default: str | None = None) -> str | None:
        return self._one(name, ("string",), default, str)

    def texture(self, name: str) -> str | None:
        return self._one(name, ("texture",), None, str)

    def floats(self, name: str) -> list[float] | None:
        p = self.find(name, ("float", "integer"))
        return None if p is None else [float(v) for v in p.values]

    def integers(self, name: str) -> list[int] | None:
        p = self.find(name, ("integer",))
        return None if p is None else [int(v) for v in p.values]

    def tuples(self, name: str, types: tuple[str, ...], size: int) -> list[tuple] | None:
        p = self.find(name, types)
        if p is None:
            return None
        if len(p.values) % size:
            raise p.error(f"expected a multiple of {size} numbers, got {len(p.values)}")
        return [tuple(float(v) for v in p.values[i:i + size]) for i in range(0, len(p.values), size)]

    def point3(self, name: str, default):
        values = self.tuples(name, ("point3", "point", "vector3", "vector", "normal3", "normal"), 3)
        if values is None:
            return tuple(default)
        if len(values) != 1:
            raise self.find(name).error("expected one point")
        return values[0]

    def unused(self) -> list[Param]:
        return [p for p in self.params if not p.used]


def read_params(stream: TokenStream) -> ParamList:
    """The parameters that follow a directive: pairs of a quoted "type name" and a value (one
    token or a bracketed list)."""
    params = ParamList()
    while (token := stream.peek()) is not None and token.quoted:
        stream.next()
        parts = token.text.split()
        if len(parts) != 2:
            raise token.error(f"parameter '{token.text}': expected \"type name\"")
        kind, name = parts
        if kind not in TYPES:
            raise token.error(f"parameter '{token.text}': unknown type '{kind}' (known: {', '.join(TYPES)})")
        params.params.append(Param(kind, name, _values(stream, token, kind), token))
    return params


def _values(stream: TokenStream, declaration: Token, kind: str) -> list:
    first = stream.next()
    if first is None:
        raise declaration.error(f"parameter '{declaration.text}' has no value")
    tokens = [first]
    if first.text == "[" and not first.quoted:
        tokens = []
        while True:
            token = stream.next()
            if token is None:
                raise first.error(f"parameter '{declaration.text}': '[' is never closed")
            if token.text == "]" and not token.quoted:
                break
            tokens.append(token)
    return [_value(token, declaration, kind) for token in tokens]


def _value(token: Token, declaration: Token, kind: str):
    if kind == "bool":
        if token.text not in ("true", "false"):
            raise token.error(f"parameter '{declaration.text}': '{token.text}' is not true or false")
        return token.text == "true"
    if kind in ("string", "texture") or (kind == "spectrum" and token.quoted):
        if not token.quoted:
            raise token.error(f"parameter '{declaration.text}': expected a quoted string, got '{token.text}'")
        return token.text
    if not token.is_number():
        raise token.error(f"parameter '{declaration.text}': '{token.text}' is not a number")
    value = float(token.text)
    if kind == "integer":
        if value != int(value):
            raise token.error(f"parameter '{declaration.text}': '{token.text}' is not an integer")
        return int(value)
    return value


def resolve(token: Token, name: str) -> Path:
    """A file a parameter names (tokenizer.find: the scene's folder, then the naming file's)."""
    return find(token, name)

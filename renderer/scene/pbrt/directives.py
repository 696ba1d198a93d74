"""pbrt-v4's directives read into a `ParsedScene`: the options before WorldBegin (Camera, Film,
Sampler, Integrator, PixelFilter), the graphics state (current transform, AttributeBegin / End,
ReverseOrientation, material, area light, MediumInterface), named things (materials, textures,
media, coordinate systems), shapes, lights and object instances, each with its file and line.
Nothing is mapped to Lantern here (scene_builder.py does that)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from renderer.scene.pbrt.parameters import ParamList, read_params
from renderer.scene.pbrt.scene_warnings import warn
from renderer.scene.pbrt.tokenizer import Token, TokenStream

IGNORED = {"Accelerator": "the acceleration structure is Lantern's own",
           "TransformTimes": "motion blur is not supported", "ActiveTransform": "motion blur is not supported"}


@dataclass
class Directive:
    name: str  # Shape, Material, LightSource, ...
    type: str  # its quoted type: "sphere", "diffuse", ...
    params: ParamList
    file: Path
    line: int
    ctm: np.ndarray = field(default_factory=lambda: np.eye(4))  # object (or light) to world
    reverse: bool = False
    material: "Directive | NamedRef | None" = None  # shapes: an anonymous Material or a named one
    area_light: "Directive | None" = None
    inside: str = ""  # shapes: MediumInterface names
    outside: str = ""
    value_type: str = ""  # Texture: "spectrum" or "float"

    @property
    def label(self) -> str:
        return f'{self.name} "{self.type}"'

    def error(self, message: str):
        from renderer.scene.errors import SceneError

        return SceneError(self.file, f"line {self.line}: {self.label}: {message}")


@dataclass(frozen=True)
class NamedRef:
    name: str
    file: Path
    line: int


@dataclass
class _State:
    ctm: np.ndarray
    reverse: bool = False
    material: "Directive | NamedRef | None" = None
    area_light: Directive | None = None
    inside: str = ""
    outside: str = ""


@dataclass
class ParsedScene:
    path: Path
    options: dict = field(default_factory=dict)  # Camera, Film, ... -> Directive
    camera_medium: str = ""
    named_materials: dict = field(default_factory=dict)
    textures: dict = field(default_factory=dict)
    media: dict = field(default_factory=dict)
    shapes: list = field(default_factory=list)
    lights: list = field(default_factory=list)
    objects: dict = field(default_factory=dict)  # name -> list of shape Directives
    instances: list = field(default_factory=list)  # (name, ctm, Token)
    files: list = field(default_factory=list)


def parse(path: Path) -> ParsedScene:
    return _Parser(Path(path)).run()


def rotation(angle: float, axis) -> np.ndarray:
    a = np.asarray(axis, np.float64)
    norm = np.linalg.norm(a)
    m = np.eye(4)
    if norm == 0.0:
        return m
    x, y, z = a / norm
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    t = math.radians(angle)
    m[:3, :3] = np.eye(3) + math.sin(t) * k + (1.0 - math.cos(t)) * (k @ k)
    return m


def look_at(eye, target, up) -> np.ndarray:
    """pbrt's LookAt: camera from world, the camera's x being up x direction (a left-handed frame)."""
    eye, target, up = (np.asarray(v, np.float64) for v in (eye, target, up))
    direction = target - eye
    if np.linalg.norm(direction) == 0.0:
        raise ValueError("the eye and the look-at point coincide")
    direction /= np.linalg.norm(direction)
    right = np.cross(up / max(np.linalg.norm(up), 1e-300), direction)
    if np.linalg.norm(right) == 0.0:
        raise ValueError("up is parallel to the viewing direction")
    right /= np.linalg.norm(right)
    world_from_camera = np.eye(4)
    world_from_camera[:3, 0], world_from_camera[:3, 1] = right, np.cross(direction, right)
    world_from_camera[:3, 2], world_from_camera[:3, 3] = direction, eye
    return np.linalg.inv(world_from_camera)


class _Parser:
    def __init__(self, path: Path):
        self.stream = TokenStream(path)
        self.scene = ParsedScene(path)
        self.state = _State(np.eye(4))
        self.stack: list[tuple[_State, Token]] = []
        self.coordinate_systems: dict[str, np.ndarray] = {}
        self.object: tuple[str, list] | None = None
        self.in_world = False

    def run(self) -> ParsedScene:
        while (token := self.stream.next()) is not None:
            if token.quoted or token.text in ("[", "]") or token.is_number():
                raise token.error(f"expected a directive, found '{token.text}'")
            handler = getattr(self, "d_" + token.text, None)
            if handler is None:
                raise token.error(f"unknown directive '{token.text}'")
            handler(token)
        if self.object is not None:
            raise self.object[2].error("ObjectBegin without a matching ObjectEnd")
        if self.stack:
            raise self.stack[-1][1].error("AttributeBegin without a matching AttributeEnd")
        self.scene.files = self.stream.files
        return self.scene

    # --- reading arguments ---------------------------------------------------------------------

    def string(self, at: Token) -> str:
        token = self.stream.next()
        if token is None or not token.quoted:
            raise at.error(f"{at.text}: expected a quoted string")
        return token.text

    def numbers(self, at: Token, count: int | None) -> list[float]:
        """`count` numbers (None: one bracketed list of any length; a list in brackets is read too)."""
        values, bracketed = [], False
        first = self.stream.peek()
        if first is not None and first.text == "[" and not first.quoted:
            self.stream.next()
            bracketed = True
        while True:
            token = self.stream.peek()
            if bracketed and token is not None and token.text == "]" and not token.quoted:
                self.stream.next()
                break
            if not bracketed and count is not None and len(values) == count:
                break
            if token is None or not token.is_number():
                if bracketed:
                    raise at.error(f"{at.text}: '[' is never closed or holds something other than numbers")
                break
            values.append(float(self.stream.next().text))
        if count is not None and len(values) != count:
            raise at.error(f"{at.text}: expected {count} numbers, got {len(values)}")
        return values

    def directive(self, at: Token) -> Directive:
        kind = self.string(at)
        return Directive(at.text, kind, read_params(self.stream), at.file, at.line)

    # --- the options block ---------------------------------------------------------------------

    def _option(self, at: Token) -> None:
        d = self.directive(at)
        if self.in_world:
            raise at.error(f"{at.text} belongs before WorldBegin")
        if at.text in IGNORED:
            return
        if at.text == "Camera":
            d.ctm = self.state.ctm.copy()  # camera from world
            try:
                self.coordinate_systems["camera"] = np.linalg.inv(d.ctm)
            except np.linalg.LinAlgError:
                raise at.error("the camera's transform is singular") from None
            self.scene.camera_medium = self.state.outside
        self.scene.options[at.text] = d

    d_Camera = d_Film = d_Sampler = d_Integrator = d_PixelFilter = d_Accelerator = _option

    def d_ColorSpace(self, at: Token) -> None:
        name = self.string(at)
        if name != "srgb":
            warn(at, f"ColorSpace '{name}' is not supported: colours are read as linear sRGB (Rec.709)")

    def d_Option(self, at: Token) -> None:
        read_params(self.stream)
        warn(at, "Option is not supported and was ignored")

    def d_WorldBegin(self, at: Token) -> None:
        self.in_world = True
        self.state.ctm = np.eye(4)
        self.coordinate_systems["world"] = np.eye(4)

    def d_WorldEnd(self, at: Token) -> None:  # pbrt-v3's; nothing to do
        pass

    # --- transforms ----------------------------------------------------------------------------

    def _apply(self, m: np.ndarray) -> None:
        self.state.ctm = self.state.ctm @ m

    def d_Identity(self, at):
        self.state.ctm = np.eye(4)

    def d_Translate(self, at):
        m = np.eye(4)
        m[:3, 3] = self.numbers(at, 3)
        self._apply(m)

    def d_Scale(self, at):
        self._apply(np.diag([*self.numbers(at, 3), 1.0]))

    def d_Rotate(self, at):
        angle, *axis = self.numbers(at, 4)
        self._apply(rotation(angle, axis))

    def d_LookAt(self, at):
        v = self.numbers(at, 9)
        try:
            self._apply(look_at(v[0:3], v[3:6], v[6:9]))
        except ValueError as e:
            raise at.error(f"LookAt: {e}") from None

    def _matrix(self, at) -> np.ndarray:
        values = self.numbers(at, None if self.stream.peek() and self.stream.peek().text == "[" else 16)
        if len(values) != 16:
            raise at.error(f"{at.text}: expected 16 numbers, got {len(values)}")
        return np.array(values, np.float64).reshape(4, 4).T  # written column by column

    def d_Transform(self, at):
        self.state.ctm = self._matrix(at)

    def d_ConcatTransform(self, at):
        self._apply(self._matrix(at))

    def d_CoordinateSystem(self, at):
        self.coordinate_systems[self.string(at)] = self.state.ctm.copy()

    def d_CoordSysTransform(self, at):
        name = self.string(at)
        if name not in self.coordinate_systems:
            raise at.error(f"CoordSysTransform: no coordinate system '{name}' (known: "
                           f"{', '.join(sorted(self.coordinate_systems)) or 'none'})")
        self.state.ctm = self.coordinate_systems[name].copy()

    def d_TransformTimes(self, at):
        self.numbers(at, 2)
        warn(at, "TransformTimes: " + IGNORED["TransformTimes"])

    def d_ActiveTransform(self, at):
        token = self.stream.next()
        if token is None or token.text not in ("StartTime", "EndTime", "All"):
            raise at.error("ActiveTransform: expected StartTime, EndTime or All")
        if token.text != "All":
            warn(at, "ActiveTransform: " + IGNORED["ActiveTransform"] + "; later transforms apply at all times")

    # --- the graphics state --------------------------------------------------------------------

    def d_AttributeBegin(self, at):
        self.stack.append((replace(self.state, ctm=self.state.ctm.copy()), at))

    def d_AttributeEnd(self, at):
        if not self.stack:
            raise at.error("AttributeEnd without a matching AttributeBegin")
        self.state = self.stack.pop()[0]

    def d_TransformBegin(self, at):  # pbrt-v3's: only the transform is saved
        self.stack.append((replace(self.state, ctm=self.state.ctm.copy()), at))

    def d_TransformEnd(self, at):
        if not self.stack:
            raise at.error("TransformEnd without a matching TransformBegin")
        self.state.ctm = self.stack.pop()[0].ctm

    def d_Attribute(self, at):
        target = self.string(at)
        read_params(self.stream)
        warn(at, f"Attribute \"{target}\": default parameters set this way are not supported and were ignored")

    def d_ReverseOrientation(self, at):
        self.state.reverse = not self.state.reverse

    def d_Material(self, at):
        self.state.material = self.directive(at)

    def d_MakeNamedMaterial(self, at):
        name = self.string(at)
        params = read_params(self.stream)
        kind = params.string("type")
        if kind is None:
            raise at.error(f"MakeNamedMaterial '{name}': needs a \"string type\"")
        self.scene.named_materials[name] = Directive("MakeNamedMaterial", kind, params, at.file, at.line)

    def d_NamedMaterial(self, at):
        self.state.material = NamedRef(self.string(at), at.file, at.line)  # resolved when the scene is built

    def d_Texture(self, at):
        name = self.string(at)
        value_type = self.string(at)
        d = self.directive(at)
        d.value_type, d.ctm = value_type, self.state.ctm.copy()
        self.scene.textures[name] = d

    def d_MakeNamedMedium(self, at):
        name = self.string(at)
        params = read_params(self.stream)
        kind = params.string("type")
        if kind is None:
            raise at.error(f"MakeNamedMedium '{name}': needs a \"string type\"")
        self.scene.media[name] = Directive("MakeNamedMedium", kind, params, at.file, at.line, ctm=self.state.ctm.copy())

    def d_MediumInterface(self, at):
        inside = self.string(at)
        nxt = self.stream.peek()
        outside = self.string(at) if nxt is not None and nxt.quoted else inside
        self.state.inside, self.state.outside = inside, outside

    def d_AreaLightSource(self, at):
        self.state.area_light = self.directive(at)

    # --- what the scene holds ------------------------------------------------------------------

    def d_LightSource(self, at):
        d = self.directive(at)
        d.ctm, d.outside = self.state.ctm.copy(), self.state.outside
        self.scene.lights.append(d)

    def d_Shape(self, at):
        d = self.directive(at)
        s = self.state
        d.ctm, d.reverse, d.material, d.area_light = s.ctm.copy(), s.reverse, s.material, s.area_light
        d.inside, d.outside = s.inside, s.outside
        (self.object[1] if self.object is not None else self.scene.shapes).append(d)

    def d_ObjectBegin(self, at):
        if self.object is not None:
            raise at.error("ObjectBegin inside another ObjectBegin")
        name = self.string(at)
        self.d_AttributeBegin(at)
        self.object = (name, [], at)

    def d_ObjectEnd(self, at):
        if self.object is None:
            raise at.error("ObjectEnd without a matching ObjectBegin")
        name, shapes, _ = self.object
        self.scene.objects[name] = shapes
        self.object = None
        self.d_AttributeEnd(at)

    def d_ObjectInstance(self, at):
        name = self.string(at)
        if name not in self.scene.objects:
            raise at.error(f"ObjectInstance: no object named '{name}'")
        self.scene.instances.append((name, self.state.ctm.copy(), at))

    def d_Include(self, at):
        token = self.stream.next()
        if token is None or not token.quoted:
            raise at.error(f"{at.text}: expected a quoted file name")
        self.stream.include(token)

    d_Import = d_Include

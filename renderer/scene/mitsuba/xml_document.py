"""A Mitsuba 3 scene file as a tree of elements, each knowing its file and line, with the file
format's own layer resolved: `<include>` spliced in, `<path>` search folders, `<default>` values and
`$name` substitution (with `-D name=value` from the command line winning over a default).

Read with the standard library's expat parser (the one ElementTree uses), which reports line and
column of malformed XML and of each element. Plugins, properties and transforms are read from the
tree by renderer/scene/mitsuba/plugins.py.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from renderer.scene.errors import SceneError
from renderer.scene.references import missing_file_problem

SUBSTITUTION = re.compile(r"\$(\w+)")
# A file that includes itself, however indirectly, is refused; so is nesting deeper than this,
# which no real scene needs and which would otherwise exhaust the stack on generated inputs.
MAX_INCLUDE_DEPTH = 32


@dataclass
class Element:
    tag: str
    attrs: dict[str, str]
    file: Path
    line: int
    children: list["Element"] = field(default_factory=list)

    def error(self, message: str) -> SceneError:
        return SceneError(self.file, f"line {self.line}: {message}")


def parse_xml_file(path: Path) -> Element:
    """The file's root element; malformed XML is one SceneError naming line and column."""
    if not path.exists():
        raise SceneError(path, missing_file_problem(path))
    if path.is_dir():
        raise SceneError(path, "is a directory, not a scene file")
    parser = expat.ParserCreate()
    stack: list[Element] = []
    root: list[Element] = []

    def start(tag, attrs):
        element = Element(tag, dict(attrs), path, parser.CurrentLineNumber)
        (stack[-1].children if stack else root).append(element)
        stack.append(element)

    def end(_tag):
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(path.read_bytes(), True)
    except expat.ExpatError as error:
        raise SceneError(path, f"line {error.lineno}, column {error.offset + 1}: malformed XML "
                               f"({expat.ErrorString(error.code)})") from None
    except OSError as error:
        raise SceneError(path, f"cannot be read ({error.strerror or error})") from None
    return root[0]


@dataclass
class Resolution:
    """What resolving the file layer keeps: parameters (from -D, then <default>), search folders."""
    parameters: dict[str, str]
    folders: list[Path]
    stack: list[Path] = field(default_factory=list)  # the files being included, outermost first
    read: list[Path] = field(default_factory=list)  # every file read besides the scene file itself

    def substitute(self, element: Element) -> dict[str, str]:
        attrs = {}
        for key, value in element.attrs.items():
            def value_of(match):
                name = match.group(1)
                if name not in self.parameters:
                    raise element.error(f"${name} has no value: give it with -D {name}=VALUE or a "
                                        f"<default name=\"{name}\" value=\"...\"/>")
                return self.parameters[name]
            attrs[key] = SUBSTITUTION.sub(value_of, value)
        return attrs

    def find(self, name: str, named_in: Path) -> Path:
        """A file a scene names, looked up as Mitsuba's file resolver does: as given when absolute,
        else in the <path> folders (latest first), then beside the file `named_in` that names it."""
        given = Path(name)
        if given.is_absolute():
            return given
        for folder in reversed(self.folders):
            if (folder / given).exists():
                return folder / given
        return named_in.parent / given


def resolve_document(path: Path, resolution: Resolution) -> Element:
    """The scene's root element with includes spliced in and every attribute substituted;
    `resolution` starts with the -D parameters and the scene's folder, and gains the rest."""
    root = parse_xml_file(Path(path))
    if root.tag != "scene":
        raise root.error(f"the root element is <{root.tag}>, not <scene>")
    return _resolve(root, resolution)


def _resolve(element: Element, resolution: Resolution) -> Element:
    attrs = resolution.substitute(element)
    resolved = Element(element.tag, attrs, element.file, element.line)
    for child in element.children:
        if child.tag == "default":
            child_attrs = resolution.substitute(child)
            _require(child, child_attrs, "name", "value")
            resolution.parameters.setdefault(child_attrs["name"], child_attrs["value"])
        elif child.tag == "path":
            child_attrs = resolution.substitute(child)
            _require(child, child_attrs, "value")
            folder = Path(child_attrs["value"])
            resolution.folders.append(folder if folder.is_absolute() else child.file.parent / folder)
        elif child.tag == "include":
            resolved.children.extend(_include(child, resolution))
        else:
            resolved.children.append(_resolve(child, resolution))
    return resolved


def _include(element: Element, resolution: Resolution) -> list[Element]:
    attrs = resolution.substitute(element)
    _require(element, attrs, "filename")
    file = resolution.find(attrs["filename"], element.file)
    if not file.exists():
        raise element.error(f"<include>: {missing_file_problem(file)}")
    real = file.resolve()
    if real in resolution.stack:
        chain = " -> ".join(p.name for p in resolution.stack[resolution.stack.index(real):] + [real])
        raise element.error(f"<include> loop: {chain}")
    if len(resolution.stack) >= MAX_INCLUDE_DEPTH:
        raise element.error(f"<include>s nested deeper than {MAX_INCLUDE_DEPTH} files")
    if file.suffix.lower() != ".xml":
        raise element.error(f"<include> of {file.name}: only Mitsuba XML files can be included")
    root = parse_xml_file(file)
    if root.tag != "scene":
        raise root.error(f"an included file's root element is <{root.tag}>, not <scene>")
    resolution.stack.append(real)
    resolution.read.append(file)
    try:
        return _resolve(root, resolution).children
    finally:
        resolution.stack.pop()


def _require(element: Element, attrs: dict[str, str], *names: str) -> None:
    missing = [name for name in names if name not in attrs]
    if missing:
        raise element.error(f"<{element.tag}> needs the attribute{'s' if len(missing) > 1 else ''} "
                            f"{', '.join(missing)}")

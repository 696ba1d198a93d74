"""pbrt-v4's token stream: quoted strings, numbers and words, [ and ], # comments, each token
with its file and line; `Include` and `Import` splice another file in where they stand, a loop
or a missing file being one SceneError line.

Relative file names (includes, meshes, images, spectra) are looked up as pbrt-v4 looks them up,
in the folder of the scene file it was given, and then in the folder of the file that names
them (`find`)."""
from __future__ import annotations

import gzip
import os
import re
from dataclasses import dataclass
from pathlib import Path

from renderer.scene.errors import SceneError
from renderer.scene.references import missing_file_problem

# A lone quote is a string that never ends on its line (pbrt's strings cannot span lines).
_TOKEN = re.compile(r'\s+|#[^\n]*|"((?:[^"\\\n]|\\.)*)"|(\[|\])|([^\s\[\]"#]+)|(")')
_ESCAPES = {"n": "\n", "t": "\t", "b": "\b", "f": "\f", "r": "\r", "\\": "\\", '"': '"', "'": "'"}


@dataclass(frozen=True)
class Token:
    text: str
    quoted: bool
    file: Path
    line: int
    base: Path | None = None  # the folder of the top-level scene file

    def error(self, message: str) -> SceneError:
        return SceneError(self.file, f"line {self.line}: {message}")

    def is_number(self) -> bool:
        if self.quoted:
            return False
        try:
            float(self.text)
        except ValueError:
            return False
        return True


def read_text(path: Path) -> str:
    data = path.read_bytes()
    if path.suffix.lower() == ".gz":
        data = gzip.decompress(data)
    return data.decode("utf-8", errors="replace")


def find(token: Token, name: str) -> Path:
    """The file a name written at `token` refers to (see the module's doc); where neither folder
    has it, the path pbrt would look for."""
    path = Path(os.path.expanduser(name))
    if path.is_absolute():
        return path
    candidates = [folder / path for folder in (token.base, token.file.parent) if folder is not None]
    return next((c for c in candidates if c.exists()), candidates[0])


def tokenize(text: str, file: Path, base: Path | None = None) -> list[Token]:
    tokens = []
    for number, line in enumerate(text.splitlines(), start=1):
        for match in _TOKEN.finditer(line):
            quoted, bracket, word, lone = match.groups()
            if lone is not None:
                raise SceneError(file, f"line {number}: a string is not terminated on its line")
            if quoted is not None:
                text_value = re.sub(r"\\(.)", lambda m: _ESCAPES.get(m.group(1), m.group(1)), quoted)
                tokens.append(Token(text_value, True, file, number, base))
            elif bracket is not None or word is not None:
                tokens.append(Token(bracket or word, False, file, number, base))
    return tokens


class TokenStream:
    """The tokens of a scene file with its includes spliced in; `files` lists every file read."""

    def __init__(self, path: Path):
        self._stack: list[list] = []  # [file, tokens, next index]
        self.files: list[Path] = []
        self.base = Path(path).parent
        self._open(path, None)

    def _open(self, path: Path, at: Token | None) -> None:
        chain = [entry[0].resolve() for entry in self._stack]
        if path.resolve() in chain:
            names = " -> ".join(p.name for p in chain[chain.index(path.resolve()):] + [path])
            raise at.error(f"include loop: {names}")
        if not path.is_file():
            if at is None:
                raise SceneError(path, missing_file_problem(path))
            raise at.error(f"cannot include '{path.name}': {missing_file_problem(path)} (looked for {path})")
        tokens = tokenize(read_text(path), path, self.base)
        if at is not None:
            self.files.append(path)
        self._stack.append([path, tokens, 0])

    def include(self, name: Token) -> None:
        """Continues with the tokens of the file `name` names, then after the Include."""
        self._open(find(name, name.text), name)

    def _top(self):
        while self._stack and self._stack[-1][2] >= len(self._stack[-1][1]):
            self._stack.pop()
        return self._stack[-1] if self._stack else None

    def peek(self) -> Token | None:
        top = self._top()
        return None if top is None else top[1][top[2]]

    def next(self) -> Token | None:
        top = self._top()
        if top is None:
            return None
        top[2] += 1
        return top[1][top[2] - 1]

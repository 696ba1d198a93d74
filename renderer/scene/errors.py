"""The one error type for bad input files (scenes, environment maps, meshes)."""
from __future__ import annotations

import os
import re
from typing import Union

PathLike = Union[str, os.PathLike]


class SceneError(Exception):
    """A problem with an input file, reported as a single line: "<file>: <problem>".

    `path` is kept exactly as the caller gave it, so the message shows the path the user typed.
    """

    def __init__(self, path: PathLike, message: str):
        # Passing both to Exception keeps the error picklable (it is rebuilt as cls(*args)).
        super().__init__(path, message)
        self.path = path
        # Callers sometimes forward multi-line messages from libraries; the contract is one line.
        self.message = re.sub(r"\s*\n\s*", " ", str(message)).strip()

    def __str__(self) -> str:
        return f"{os.fspath(self.path)}: {self.message}"

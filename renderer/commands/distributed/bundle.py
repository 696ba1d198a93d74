"""A scene's files packed for other machines: the scene (or model) file and every file it reads.

Workers on the driver's machine, or on nodes that see the same files at the same paths, read them
in place (checked by content hash); others unpack the bundle into a temporary folder keeping the
files' layout relative to their common folder, so relative references in the scene resolve there.
"""
from __future__ import annotations

import hashlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

from renderer.output.checkpoint import scene_files
from renderer.scene.description import Scene


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


@dataclass(frozen=True)
class SceneBundle:
    root: str  # the common folder of the files on the driver's machine
    entry: str  # the scene or model file, relative to root
    files: dict[str, bytes]  # relative path -> content
    digests: dict[str, str]  # relative path -> sha256 of content

    @classmethod
    def of(cls, scene: Scene) -> "SceneBundle":
        paths = scene_files(scene)
        root = Path(os.path.commonpath([str(p.parent) for p in paths]))
        files = {p.relative_to(root).as_posix(): p.read_bytes() for p in paths}
        return cls(str(root), Path(scene.path).resolve().relative_to(root).as_posix(), files,
                   {name: _digest(data) for name, data in files.items()})

    @property
    def size(self) -> int:
        """Bytes shipped."""
        return sum(len(data) for data in self.files.values())

    def in_place(self) -> Path | None:
        """The entry file at its original path if every file is there with the same content."""
        root = Path(self.root)
        for name, digest in self.digests.items():
            path = root / name
            try:
                if not path.is_file() or _digest(path.read_bytes()) != digest:
                    return None
            except OSError:
                return None
        return root / self.entry

    def unpack(self, folder: Path | None = None) -> Path:
        """Write the files under `folder` (default: a new temporary folder); the entry file's path."""
        folder = Path(folder or tempfile.mkdtemp(prefix="lantern-scene-"))
        for name, data in self.files.items():
            path = folder / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
        return folder / self.entry

    def scene_path(self) -> Path:
        """Where a worker reads the scene: in place, else unpacked."""
        return self.in_place() or self.unpack()

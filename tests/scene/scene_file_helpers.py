"""Helpers of the scene-file loader tests: minimal TOML scene texts, writing them, and the
one-line error contract of a bad scene."""
from __future__ import annotations

from pathlib import Path

import pytest

from renderer.scene import SceneError, SdfNode, Transform, load_scene

REPO = Path(__file__).resolve().parents[2]

HEADER = '[scene]\ngeometry = "sdf"\n'
MATERIAL = "[materials.m]\n"
SPHERE = '[[objects]]\ntype = "sphere"\nmaterial = "m"\n'


def scene_text(extra: str = "", objects: str = SPHERE, materials: str = MATERIAL,
               header: str = HEADER) -> str:
    """A valid minimal scene with `extra` sections inserted (TOML forbids redefining tables)."""
    return header + extra + "\n" + materials + "\n" + objects


def write(tmp_path: Path, text: str, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def load_error(path) -> str:
    """Load a bad scene and check the message contract: one line, starting with the path."""
    with pytest.raises(SceneError) as info:
        load_scene(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    return message


def node(kind: str, params=(), children=(), material=None, transform=Transform()) -> SdfNode:
    return SdfNode(kind=kind, params=tuple(sorted(params)), children=tuple(children),
                   transform=transform, material=material)

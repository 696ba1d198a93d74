"""What the user allowed when loading a scene: the memory budget and files outside a model's folder.

Passed explicitly from the command line through the scene loaders to every reader (never kept
in a global), so two scenes loaded side by side can follow different rules.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from renderer.scene.limits import MemoryBudget


@dataclass(frozen=True)
class LoadOptions:
    budget: MemoryBudget = field(default_factory=MemoryBudget.from_settings)
    # A model's references (glTF URIs, OBJ mtllib and maps, PLY TextureFile) must stay inside the
    # model's folder unless this is set (--allow-outside-files): a downloaded model must not read
    # files elsewhere on the machine. Scene files may name any file: the user wrote them.
    allow_outside_files: bool = False
    # A Mitsuba scene's parameters from the command line (-D name=value), overriding its <default>s.
    defines: tuple[tuple[str, str], ...] = ()


def options_from_arguments(args) -> LoadOptions:
    """The options a command line asked for (`--memory-limit`, `--allow-outside-files`, `-D`;
    commands without them get the defaults)."""
    return LoadOptions(MemoryBudget.from_settings(getattr(args, "memory_limit", None)),
                       bool(getattr(args, "allow_outside_files", False)),
                       parse_defines(getattr(args, "define", None) or ()))


def parse_defines(items) -> tuple[tuple[str, str], ...]:
    """NAME=VALUE strings (-D) as pairs; a malformed one is a ValueError naming it."""
    pairs = []
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not name.strip().replace("_", "a").isalnum():
            raise ValueError(f"-D {item}: expected NAME=VALUE")
        pairs.append((name.strip(), value))
    return tuple(pairs)

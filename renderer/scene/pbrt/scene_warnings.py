"""The pbrt reader's warnings: one line naming file, line and directive for what Lantern leaves
out or approximates."""
from __future__ import annotations

import warnings


class PbrtSceneWarning(UserWarning):
    """Something a pbrt-v4 scene asks for that Lantern leaves out or approximates."""


def warn(where, message: str) -> None:
    """`where`: anything with file, line and label (a directive), or a Token."""
    label = getattr(where, "label", None)
    prefix = f"{where.file}: line {where.line}: " + (f"{label}: " if label else "")
    warnings.warn(prefix + message, PbrtSceneWarning, stacklevel=3)


def warn_unused(directive) -> None:
    for p in directive.params.unused():
        p.used = True
        line = "" if p.token.line == directive.line else f" (line {p.token.line})"
        warn(directive, f"parameter {p.label}{line} is not supported and was ignored")

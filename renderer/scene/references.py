"""Files that input files name: resolved with symlinks followed, and kept inside a model's folder.

A model file is often downloaded: its references (glTF URIs, OBJ `mtllib` and texture maps, a
PLY `TextureFile`) may only reach files inside the model's own folder (after following symlinks),
unless the user allows more (`LoadOptions.allow_outside_files`). Every problem is a one-line
SceneError naming the file that holds the reference.
"""
from __future__ import annotations

from pathlib import Path

from renderer.scene.errors import PathLike, SceneError


def real_path(path: Path, shown: PathLike) -> Path:
    """`path` with every symlink followed, or a SceneError naming `shown` for a symlink loop."""
    try:
        return path.resolve()
    except (RuntimeError, OSError) as error:  # RuntimeError: Python's report of a symlink loop
        raise SceneError(shown, f"symlink loop at {path}" if isinstance(error, RuntimeError)
                         else f"cannot resolve {path} ({error.strerror or error})") from None


def missing_file_problem(path: Path) -> str:
    """Why `path` cannot be read as a file, in a few words."""
    if path.is_symlink():
        try:
            path.resolve(strict=True)
        except RuntimeError:
            return "symlink loop"
        except OSError:
            return "broken symlink"
    if path.is_dir():
        return "is a directory, not a file"
    return "file not found"


def resolve_reference(model: Path, shown: PathLike, reference: str, what: str, allow_outside: bool,
                      base: Path | None = None) -> Path:
    """The file `reference` (relative to `base`, by default the model's folder) that the model
    file `model` names as `what`; refused unless it lies inside the model's folder or
    `allow_outside` is set. Errors name `shown`, the model as the user gave it."""
    target = (base or model.parent) / reference
    resolved = real_path(target, shown)
    if allow_outside:
        return resolved
    root = real_path(model.parent, shown)
    if not resolved.is_relative_to(root):  # "../..", an absolute path or a symlink leading out
        raise SceneError(shown, f"{what} '{reference}' lies outside the model's folder {root} "
                                "(--allow-outside-files reads it anyway)")
    return resolved

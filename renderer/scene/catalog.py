"""The scenes that ship in assets/scenes, and resolution of a SCENE argument to a file."""
from pathlib import Path

from renderer.scene.errors import SceneError
from renderer.scene.load_options import LoadOptions
from renderer.scene.references import missing_file_problem

ASSETS = Path(__file__).resolve().parents[2] / "assets"
SCENES_DIR = ASSETS / "scenes"
# The viewer's order (next/previous scene); scenes not listed follow alphabetically.
PREFERRED_ORDER = ("showcase", "mirror_field", "hard_cases", "foggy", "prism", "cornell_box", "bunnies", "weekend", "textured",
                   "many_lights", "studio", "pool", "goblet", "stress")
DEFAULT_SCENE = "showcase"


def scene_files() -> list[Path]:
    files = {p.stem: p for p in SCENES_DIR.glob("*.toml")}
    ordered = [files.pop(name) for name in PREFERRED_ORDER if name in files]
    return ordered + [files[k] for k in sorted(files)]


def scene_names() -> list[str]:
    return [p.stem for p in scene_files()]


def load_any(path, options: LoadOptions | None = None):
    """A scene file (Lantern's .toml, a TOML scene of edits of another file, Mitsuba 3's .xml, pbrt-v4's .pbrt) or a model file (glTF/GLB, OBJ, PLY, STL) as a
    Scene, read under `options` (memory budget, files outside a model's folder, -D parameters;
    default LoadOptions())."""
    from renderer.scene.edits_file import load_toml_scene
    from renderer.scene.foreign_formats import is_foreign, load_foreign

    options = options or LoadOptions()
    return load_foreign(path, options) if is_foreign(path) else load_toml_scene(path, options)


def resolve_scene(argument: str) -> Path:
    """A scene name from assets/scenes, or a path to a scene file."""
    path = Path(argument)
    if path.suffix or path.exists() or "/" in argument:
        if not path.exists():
            raise SceneError(argument, missing_file_problem(path))
        return path
    for candidate in scene_files():
        if candidate.stem == argument:
            return candidate
    raise SceneError(argument, f"unknown scene (known: {', '.join(scene_names())}; or give a file path)")

"""The scene files Lantern opens besides its own TOML: Mitsuba 3's .xml, pbrt-v4's .pbrt (and
.pbrt.gz), and model files (glTF/GLB, OBJ, PLY, STL) opened as a scene of their own."""
from __future__ import annotations

from pathlib import Path

from renderer.scene.description import Scene
from renderer.scene.load_options import LoadOptions


def _format(path) -> str:
    from renderer.scene.model_formats import MESH_EXTENSIONS

    name = Path(path).name.lower()
    if name.endswith(".xml"):
        return "mitsuba"
    if name.endswith((".pbrt", ".pbrt.gz")):
        return "pbrt"
    return "model" if Path(path).suffix.lower() in MESH_EXTENSIONS else ""


def is_foreign(path) -> bool:
    """Whether `path` names a scene in a format other than Lantern's TOML."""
    return bool(_format(path))


def load_foreign(path, options: LoadOptions) -> Scene:
    """The scene of a Mitsuba, pbrt or model file (is_foreign(path) must hold)."""
    kind = _format(path)
    if kind == "mitsuba":
        from renderer.scene.mitsuba import load_mitsuba_scene

        return load_mitsuba_scene(path, options)
    if kind == "pbrt":
        from renderer.scene.pbrt import load_pbrt_scene

        return load_pbrt_scene(path, options)
    from renderer.scene.model_scene import scene_for_model

    return scene_for_model(path, options)

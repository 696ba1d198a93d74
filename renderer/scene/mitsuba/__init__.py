"""Mitsuba 3 scene files (.xml) read into Lantern's plain scene description.

xml_document.py       the XML with Mitsuba's file layer resolved: <include>, <path>, <default>, $name, -D
plugins.py            objects, typed properties, <ref>s and transforms
scene_builder.py      plugins -> Scene: camera, render settings, materials, shapes, environment
shapes.py             shapes, shape groups and instances -> mesh objects
emitters.py           emitters -> the environment, lights (point, spot, directional, projector), area emission
mesh_attribute_textures.py   mesh_attribute textures (and diffuse blends) -> a material's MeshAttributeColor
scene_warnings.py     MitsubaSceneWarning: one line for what is left out or approximated
ior_names.py          the named indices of refraction (int_ior="bk7")
"""
from __future__ import annotations

from pathlib import Path

from renderer.scene.description import Scene
from renderer.scene.load_options import LoadOptions
from renderer.scene.mitsuba.plugins import read_plugins
from renderer.scene.mitsuba.scene_builder import build_scene
from renderer.scene.mitsuba.scene_warnings import MitsubaSceneWarning
from renderer.scene.mitsuba.xml_document import Resolution, resolve_document
from renderer.scene.model_files import ModelFiles

__all__ = ["load_mitsuba_scene", "MitsubaSceneWarning"]


def load_mitsuba_scene(path, options: LoadOptions | None = None) -> Scene:
    """Read a Mitsuba 3 scene; `options.defines` are its -D name=value parameters. Problems are one
    SceneError line naming file and line; what Lantern leaves out is one MitsubaSceneWarning each."""
    options = options or LoadOptions()
    path = Path(path)
    resolution = Resolution(dict(options.defines), [path.parent], [path.resolve()])
    root = resolve_document(path, resolution)
    return build_scene(read_plugins(root, resolution), path, resolution, ModelFiles(options), dict(options.defines))

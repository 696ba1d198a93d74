"""pbrt-v4 scene files (.pbrt, .pbrt.gz) read into Lantern's plain scene description.

tokenizer.py       tokens with file and line; Include and Import spliced in
parameters.py      typed parameter lists ("float fov" [45]), each remembering whether it was read
directives.py      directives -> ParsedScene: options, graphics state, transforms, named things
spectra.py         rgb, spectrum, blackbody and named spectra made RGB
scene_builder.py   ParsedScene -> Scene: camera (and pbrt's left-handed image), film, sampler,
                   integrator, pixel filter, shapes placed, the mirror where pbrt's image needs one
materials.py       materials, textures (imagemap, checkerboard, scale) and homogeneous media
shapes.py          shapes -> mesh objects; inline_meshes.py the meshes written in the file
lights.py          light sources -> lights and the environment; area lights -> emission
environment_map.py pbrt's equal-area square maps resampled into latitude-longitude maps
scene_warnings.py  PbrtSceneWarning: one line for what is left out or approximated
format_doc.py      the "pbrt-v4 scenes" section of docs/scene-format.md
"""
from __future__ import annotations

from pathlib import Path

from renderer.scene.description import Scene
from renderer.scene.load_options import LoadOptions
from renderer.scene.pbrt.directives import parse
from renderer.scene.pbrt.inline_meshes import PbrtModelFiles
from renderer.scene.pbrt.scene_builder import build_scene
from renderer.scene.pbrt.scene_warnings import PbrtSceneWarning

__all__ = ["load_pbrt_scene", "PbrtSceneWarning", "is_pbrt_file"]


def is_pbrt_file(path) -> bool:
    name = Path(path).name.lower()
    return name.endswith(".pbrt") or name.endswith(".pbrt.gz")


def load_pbrt_scene(path, options: LoadOptions | None = None) -> Scene:
    """Read a pbrt-v4 scene. Problems are one SceneError line naming file and line; what Lantern
    leaves out is one PbrtSceneWarning each."""
    path = Path(path)
    parsed = parse(path)
    return build_scene(parsed, PbrtModelFiles(options or LoadOptions(), path))

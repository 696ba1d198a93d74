"""Small pbrt-v4 files written by the tests, loaded with their warnings collected."""
from __future__ import annotations

import warnings

from renderer.scene.pbrt import PbrtSceneWarning, load_pbrt_scene

CAMERA = """LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [45]
Film "rgb" "integer xresolution" [16] "integer yresolution" [12]
"""
SPHERE = 'Shape "sphere" "float radius" [0.5]\n'


def write(tmp_path, text: str, name: str = "s.pbrt"):
    path = tmp_path / name
    path.write_text(text)
    return path


def load(tmp_path, world: str, options: str = CAMERA, expect_warnings: int = 0):
    """A scene of `options`, WorldBegin, `world`; returns (scene, warning messages)."""
    path = write(tmp_path, options + "WorldBegin\n" + world)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = load_pbrt_scene(path)
    messages = [str(w.message) for w in caught if issubclass(w.category, PbrtSceneWarning)]
    assert len(messages) == expect_warnings, messages
    return scene, messages


def material(scene, name: str):
    return next(m for m in scene.materials if m.name == name)

"""Renders of mesh scenes: shading normals keep a furnace exact (no black seams), the Cornell box
and textured scenes render finite, and model files open as scenes."""
import numpy as np
import pytest
import trimesh

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.description import CameraSpec, EnvironmentSpec, MaterialSpec, MeshObject, RenderSettings, Scene


def furnace_scene(tmp_path, subdivisions=1):
    """A coarse sphere with smooth vertex normals, albedo 1, under a constant sky of 0.5."""
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions)
    path = tmp_path / "ball.obj"
    mesh.export(path, include_normals=True)
    return Scene(name="furnace", path=None, geometry="mesh",
                 camera=CameraSpec(position=(0.0, 0.0, 3.0), look_at=(0.0, 0.0, 0.0), fov=45.0),
                 render=RenderSettings(width=40, height=40, max_depth=-1),
                 environment=EnvironmentSpec(kind="constant", color=(0.5, 0.5, 0.5)),
                 materials=(MaterialSpec("white", "diffuse", (1.0, 1.0, 1.0)),),
                 mesh_objects=(MeshObject(kind="mesh", file=path, material="white"),))


@pytest.mark.parametrize("integrator", ["path", "mis"])
def test_smooth_shading_normals_neither_blacken_nor_leak(tmp_path, integrator):
    """An 80-face sphere with interpolated normals, albedo 1, under a constant sky of 0.5.

    Interpolated normals tilt away from the viewer at silhouettes; without the consistency fix
    those hits shade black (seams). Directions that the shading normal accepts but that cross the
    true surface are refused (pbrt's rule), else light leaks in and out through the faces: with
    light sampling that showed as pixels brighter than the sky (energy gain). The refusals cost a
    little energy where normals tilt most, never all of it."""
    scene = furnace_scene(tmp_path)
    r = Renderer(scene)
    assert r.geometry.has_normals
    r.render(CameraFrame.from_spec(scene.camera), 64, integrator=integrator)
    img = r.image()[..., 1]
    # No seam: a black pixel would be 0; every pixel keeps most of the sky's radiance.
    assert img.min() > 0.25, f"darkest pixel {img.min():.3f}"
    # No leak: no pixel significantly above the sky. One-sided z > 4.5 has probability 3.4e-6
    # per pixel, so by chance anywhere in the 1,600 pixels with probability ~5e-3.
    sigma = np.sqrt(np.maximum(r.film.variance_of_mean_image()[..., 1], 1e-12))
    excess = (img - 0.5) / sigma
    assert excess.max() < 4.5, f"pixel {excess.max():.1f} sigma above the sky: light leaks in"


def test_model_file_opens_as_scene():
    from renderer.scene.catalog import load_any

    scene = load_any("assets/models/bunny.glb")
    assert scene.geometry == "mesh" and scene.mesh_objects[0].file.name == "bunny.glb"
    r = Renderer(scene, (32, 18))
    r.render(CameraFrame.from_spec(scene.camera), 1, integrator="albedo")
    img = r.image()
    covered = (img.sum(axis=-1) > 0).mean()
    assert 0.05 < covered < 0.9, "the framed model fills part of the view"

"""Instanced model files render like the same placements flattened (image z-test), the
SimpleInstancing stand-in renders, and a thousand instances of a 20k-triangle mesh load with one
copy of its triangles and render.

Where the claim is about geometry (the z-test, the crowd), the model files' glTF materials are
overridden by diffuse ones, one per object: a kernel with the principled BSDF takes three to four
times as long to compile (a fresh suite compiles every kernel) and is not what these tests
compare. The stand-in test renders a model file as it opens, principled materials and environment
map included."""
import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

from renderer.camera import CameraFrame
from renderer.renderer import MeshOptions, Renderer
from renderer.scene.catalog import load_any
from renderer.scene.description import CameraSpec, EnvironmentSpec, MaterialSpec, MeshObject, RenderSettings, Scene
from tests.data import make_test_models as models
from tests.stats.image_tests import assert_agree

DATA = Path(__file__).resolve().parents[1] / "data"
# Model files open under the default environment map, whose few negative texels warn.
pytestmark = pytest.mark.filterwarnings("ignore::renderer.output.image_io.NegativePixelsWarning")


def quiet_load(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the default environment map may warn
        return load_any(path)


def rendered(scene, spp, integrator, seed, options=MeshOptions()):
    r = Renderer(scene, mesh_options=options)
    r.render(CameraFrame.from_spec(scene.camera), spp, integrator=integrator, seed=seed)
    return r


def test_simple_instancing_stand_in_renders():
    scene = quiet_load(DATA / "simple_instancing.gltf")
    r = rendered(scene, 2, "mis", 0)
    assert r.features().has_instances and r.geometry.instances.count == 64
    assert len(r.geometry.data.tri_vertices) == 12  # one cube, drawn 64 times
    image = r.image()
    assert np.isfinite(image).all() and image.mean() > 0.01


def test_instanced_image_agrees_with_flattened():
    """tests/data/instancing.gltf (two placements of a box, one mirrored, and three of another by
    EXT_mesh_gpu_instancing, one mirrored, one non-uniformly scaled) and simple_instancing.gltf
    in one scene, rendered with its instances and with every instance flattened into world
    triangles, different seeds: the images agree by the per-pixel and image-mean z-tests."""
    # A colour per object (materials overridden, see the module doc): instances must still find
    # their object's material.
    scene = Scene(name="instances", path=None, geometry="mesh",
                  camera=CameraSpec(position=(6.0, 14.0, 22.0), look_at=(0.0, 4.0, 0.0), fov=50.0),
                  render=RenderSettings(width=40, height=30, max_depth=4),
                  environment=EnvironmentSpec(kind="sky"),
                  materials=(MaterialSpec("floor", "diffuse", (0.6, 0.6, 0.6)),
                             MaterialSpec("boxes", "diffuse", (0.9, 0.9, 0.9)),
                             MaterialSpec("cubes", "diffuse", (0.8, 0.5, 0.2))),
                  mesh_objects=(MeshObject(kind="mesh", file=DATA / "instancing.gltf", material="boxes"),
                                MeshObject(kind="mesh", file=DATA / "simple_instancing.gltf", material="cubes",
                                           translate=(0.0, 6.0, 0.0), rotate=(0.0, 30.0, 0.0), scale=(1.0, 0.5, 2.0)),
                                MeshObject(kind="quad", material="floor", size=(60.0, 60.0),
                                           translate=(0.0, -6.0, 0.0))))
    spp = 96
    a = rendered(scene, spp, "mis", 1)
    b = rendered(scene, spp, "mis", 2, MeshOptions(instancing=False))
    assert a.features().has_instances and not b.features().has_instances
    assert len(a.geometry.data.tri_vertices) < len(b.geometry.data.tri_vertices)
    assert_agree((a.image(), a.film.variance_of_mean_image()), (b.image(), b.film.variance_of_mean_image()),
                 ("instanced", "flattened"))


def sphere_crowd(path: Path, subdivisions=5, count=1000):
    """A glTF of one icosphere (20,480 triangles at 5 subdivisions) drawn `count` times by
    EXT_mesh_gpu_instancing on a square grid, with varied scales."""
    ball = trimesh.creation.icosphere(subdivisions=subdivisions)
    b = models.BufferBuilder()
    side = math.ceil(math.sqrt(count))
    k = np.arange(count)
    translations = np.stack([k % side * 2.5, np.zeros(count), k // side * 2.5], axis=1).astype(np.float32)
    scales = np.repeat((0.6 + 0.4 * (k % 5) / 4)[:, None], 3, axis=1).astype(np.float32)
    sphere = {"attributes": {"POSITION": b.accessor(np.asarray(ball.vertices, np.float32)),
                             "NORMAL": b.accessor(np.asarray(ball.vertex_normals, np.float32))},
              "indices": b.accessor(np.asarray(ball.faces, np.uint32).reshape(-1))}
    gpu = {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": b.accessor(translations),
                                                      "SCALE": b.accessor(scales)}}}
    doc = {"asset": {"version": "2.0"}, "extensionsUsed": ["EXT_mesh_gpu_instancing"],
           "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"mesh": 0, "extensions": gpu}], "meshes": [{"primitives": [sphere]}],
           "accessors": b.accessors, "bufferViews": b.views, "buffers": models.data_uri_buffer(b)}
    path.write_text(json.dumps(doc))
    return len(ball.faces)


@pytest.fixture(scope="module")
def crowd(tmp_path_factory):
    """(the crowd's Renderer, the icosphere's triangle count): loaded once for both integrators.
    The spheres are white diffuse (materials overridden, see the module doc) under a grey sky; the
    camera looks down on the grid, 64x36 pixels (the claim does not depend on the image size)."""
    path = tmp_path_factory.mktemp("crowd") / "crowd.gltf"
    triangles = sphere_crowd(path)
    scene = Scene(name="crowd", path=None, geometry="mesh",
                  camera=CameraSpec(position=(38.75, 40.0, 110.0), look_at=(38.75, 0.0, 38.75), fov=50.0),
                  render=RenderSettings(width=64, height=36),
                  environment=EnvironmentSpec(kind="constant", color=(0.5, 0.5, 0.5)),
                  materials=(MaterialSpec("white", "diffuse", (0.8, 0.8, 0.8)),),
                  mesh_objects=(MeshObject(kind="mesh", file=path, material="white"),))
    return Renderer(scene), triangles


@pytest.mark.parametrize("integrator", ["mis", "sppm"])
def test_a_thousand_instances_of_a_large_mesh_load_and_render(crowd, integrator):
    r, triangles = crowd
    assert r.geometry.instances.count == 1000 and len(r.geometry.data.tri_vertices) == triangles
    memory = r.geometry.device_bytes()
    # One copy of the sphere and ~172 bytes per instance; flattened it would be ~2.3 GB.
    per_copy = triangles * (36 + 36) + 2 * triangles * 36
    assert memory["total"] < per_copy + 1000 * 200, memory
    r.reset()
    r.render(CameraFrame.from_spec(r.scene.camera), 2, integrator=integrator, seed=0)
    image = r.image()
    assert np.isfinite(image).all() and (image.sum(axis=-1) > 0).mean() > 0.5

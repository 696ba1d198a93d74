"""Any model file as a scene: its own materials, a camera framed on its bounds, a floor-less
default HDR environment. What `app.py view model.glb` and `render model.obj` open."""
from pathlib import Path

from renderer.scene.load_options import LoadOptions
from renderer.scene.framing import frame_camera
from renderer.scene.description import CameraSpec, EnvironmentSpec, MeshObject, RenderSettings, Scene
from renderer.scene.model_files import ModelFiles

ASSETS = Path(__file__).resolve().parents[2] / "assets"
# A soft, low-contrast map (peak ~7): models read clearly and converge fast under it.
DEFAULT_ENVIRONMENT = ASSETS / "envmaps" / "venice.exr"
FOV = 40.0
SIZE = (640, 360)


def scene_for_model(path, options: LoadOptions | None = None) -> Scene:
    path = Path(path)
    files = ModelFiles(options)  # the scene keeps the parsed file: assembly reads it from there
    asset = files.load(path)  # one-line SceneError for a bad file, before anything else
    position, target = frame_camera(asset.bounds, FOV, aspect=SIZE[0] / SIZE[1])
    distance = sum((a - b) ** 2 for a, b in zip(position, target)) ** 0.5
    return Scene(
        name=path.stem, path=path, geometry="mesh",
        camera=CameraSpec(position=position, look_at=target, fov=FOV, focus_distance=distance),
        render=RenderSettings(width=SIZE[0], height=SIZE[1]),
        environment=EnvironmentSpec(kind="map", file=DEFAULT_ENVIRONMENT),
        materials=(), mesh_objects=(MeshObject(kind="mesh", file=path),),
        description=f"{path.name}: {asset.triangle_count} triangles, {len(asset.materials)} materials",
        model_files=files)

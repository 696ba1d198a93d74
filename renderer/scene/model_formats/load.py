"""The one entry point of model files: the reader chosen by the file's extension, and every failure
inside a reader said in one line naming the file."""
from __future__ import annotations

from pathlib import Path
from typing import Optional

from renderer.scene.errors import PathLike, SceneError
from renderer.scene.limits import MemoryLedger
from renderer.scene.load_options import LoadOptions
from renderer.scene.mesh_model import MeshAsset
from renderer.scene.model_formats.builder import AssetBuilder
from renderer.scene.model_formats.gltf import GltfReader
from renderer.scene.model_formats.obj_mtl import read_obj
from renderer.scene.model_formats.ply_stl import read_ply, read_stl
from renderer.scene.model_formats.serialized import read_serialized
from renderer.scene.references import missing_file_problem

MESH_EXTENSIONS = (".gltf", ".glb", ".obj", ".ply", ".stl", ".serialized")


def load_mesh_asset(path: PathLike, options: Optional[LoadOptions] = None,
                    ledger: Optional[MemoryLedger] = None) -> MeshAsset:
    """Load a .gltf, .glb, .obj, .ply, .stl or (Mitsuba's) .serialized model (what is read: each
    format's module; checks: the package).

    `options`: the memory budget and whether references may leave the model's folder (default:
    `LoadOptions()`); `ledger`: where the scene adds up what its files were charged (default: a
    new one over the options' budget)."""
    name = path  # errors show the path exactly as the caller gave it
    file = Path(path)
    if not file.is_file():
        problem = missing_file_problem(file)
        raise SceneError(name, "model file not found" if problem == "file not found" else problem)
    extension = file.suffix.lower()
    if extension not in MESH_EXTENSIONS:
        raise SceneError(
            name,
            f"unsupported model format '{file.suffix or '(none)'}' "
            f"(expected one of {', '.join(MESH_EXTENSIONS)})",
        )
    options = options or LoadOptions()
    builder = AssetBuilder(name, file, options, ledger or MemoryLedger(options.budget))
    try:
        builder.charge_file(file, "the file")
        if extension in (".gltf", ".glb"):
            GltfReader(builder).read()
        elif extension == ".obj":
            read_obj(builder)
        elif extension == ".ply":
            read_ply(builder)
        elif extension == ".serialized":
            read_serialized(builder)
        else:
            read_stl(builder)
        return builder.finish()
    except SceneError:
        raise
    except Exception as e:  # noqa: BLE001 - the readers (ours, trimesh, numpy) raise many types
        # for bad data; every one is a problem with this file, said in one line
        detail = f"{type(e).__name__}: {e}" if str(e) else type(e).__name__
        raise SceneError(name, f"cannot read {extension[1:].upper()} file ({detail})") from e

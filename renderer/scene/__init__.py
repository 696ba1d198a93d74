"""Scenes as plain data: the description (description.py: dataclasses), its file format (schema.py)
and TOML loader, the catalogue of shipped scenes, and model files opened as scenes."""
from .errors import SceneError
from .description import (
    ENVIRONMENT_KINDS,
    GEOMETRY_KINDS,
    MATERIAL_KINDS,
    SDF_OPERATORS,
    SDF_PRIMITIVES,
    CameraSpec,
    EnvironmentSpec,
    MarchSettings,
    MaterialSpec,
    RenderSettings,
    Scene,
    SdfNode,
    Transform,
)
from .toml_loader import load_scene

__all__ = [
    "load_scene",
    "SceneError",
    "CameraSpec",
    "EnvironmentSpec",
    "MarchSettings",
    "MaterialSpec",
    "RenderSettings",
    "Scene",
    "SdfNode",
    "Transform",
    "ENVIRONMENT_KINDS",
    "GEOMETRY_KINDS",
    "MATERIAL_KINDS",
    "SDF_OPERATORS",
    "SDF_PRIMITIVES",
]

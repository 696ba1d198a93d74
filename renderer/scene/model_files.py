"""The model files one scene reads, each parsed once.

A `Scene` carries a `ModelFiles`: the code that frames a model's camera (model_scene) and the code
that assembles the device arrays (mesh_assembly) both ask it for the same file and get the same
`MeshAsset`, so a model is read and decoded once per run. It belongs to its scene, not to the
process: nothing is shared between scenes, and it goes away with the scene.
"""
from __future__ import annotations

import os
from pathlib import Path


class ModelFiles:
    def __init__(self):
        self._assets: dict[Path, object] = {}

    def load(self, path: str | os.PathLike):
        """The `MeshAsset` of a model file, parsed on first use (errors name `path` as given)."""
        key = Path(path).resolve()
        if key not in self._assets:
            from renderer.scene.mesh_loader import load_mesh_asset  # the loader imports the model

            self._assets[key] = load_mesh_asset(path)
        return self._assets[key]

    def __len__(self) -> int:
        return len(self._assets)

    def __repr__(self) -> str:
        return f"ModelFiles({len(self._assets)} loaded)"

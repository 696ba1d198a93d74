"""The model files one scene reads, each parsed once, under the scene's load options.

A `Scene` carries a `ModelFiles`: the code that frames a model's camera (model_scene) and the code
that assembles the scene's primitives (mesh_assembly) both ask it for the same file and get the same
`MeshAsset`, so a model is read and decoded once per run. It belongs to its scene, not to the
process: nothing is shared between scenes, and it goes away with the scene. Its `ledger` adds up
the memory every model of the scene was charged (renderer.scene.limits), and its `options`
(budget, files outside a model's folder) are what the user allowed for this scene.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Optional

from renderer.scene.limits import MemoryLedger
from renderer.scene.load_options import LoadOptions
from renderer.scene.model_formats import load_mesh_asset
from renderer.scene.references import real_path


class ModelFiles:
    def __init__(self, options: Optional[LoadOptions] = None):
        self.options = options or LoadOptions()
        self.ledger = MemoryLedger(self.options.budget)
        self._assets: dict[Path, object] = {}

    def load(self, path: str | os.PathLike):
        """The `MeshAsset` of a model file, parsed on first use (errors name `path` as given)."""
        key = real_path(Path(path), path)
        if key not in self._assets:
            self._assets[key] = load_mesh_asset(path, self.options, self.ledger)
        return self._assets[key]

    def __len__(self) -> int:
        return len(self._assets)

    def __repr__(self) -> str:
        return f"ModelFiles({len(self._assets)} loaded)"

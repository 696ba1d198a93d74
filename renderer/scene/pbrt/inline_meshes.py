"""Meshes written inside a pbrt file (trianglemesh, bilinearmesh) and gzip-compressed PLY files,
gathered into one model asset keyed by the scene file itself: each is a mesh `part` of it, so
mesh objects name them as they name a model file's parts (and a checkpoint's fingerprint covers
the scene file they came from)."""
from __future__ import annotations

import gzip
import io
from pathlib import Path

import numpy as np

from renderer.scene.model_files import ModelFiles
from renderer.scene.model_formats.builder import AssetBuilder, default_grey


class PbrtModelFiles(ModelFiles):
    def __init__(self, options, scene_path: Path):
        super().__init__(options)
        self.scene_path = Path(scene_path)
        self._builder = AssetBuilder(scene_path, self.scene_path, self.options, self.ledger)
        default_grey(self._builder)
        self._asset = None
        self.count = 0

    def add(self, positions, indices, normals=None, uv=None) -> str:
        """Adds a mesh in its own frame; returns its part name. pbrt's v points up an image,
        Lantern's down: v is turned over here, as Lantern's PLY reader turns it."""
        if uv is not None:
            uv = np.asarray(uv, np.float64).reshape(-1, 2).copy()
            uv[:, 1] = 1.0 - uv[:, 1]
        part = f"mesh {self.count}"
        self.count += 1
        self._builder.add_mesh(part, positions, indices, normals=normals, uv0=uv, name=part)
        self._asset = None
        return part

    def add_gzipped_ply(self, path: Path) -> str:
        from trimesh.exchange.ply import load_ply

        with gzip.open(path, "rb") as f:
            data = f.read()
        self._builder.charge("a decompressed PLY file", len(data))
        kwargs = load_ply(io.BytesIO(data), fix_texture=True, skip_materials=True)
        vertices, faces = kwargs.get("vertices"), kwargs.get("faces")
        if vertices is None or faces is None or len(faces) == 0:
            raise ValueError("contains no triangles")
        uv = getattr(kwargs.get("visual"), "uv", None)
        return self.add(vertices, np.asarray(faces).reshape(-1, 3), kwargs.get("vertex_normals"),
                        None if uv is None else np.asarray(uv, np.float64)[:, :2])

    def load(self, path):
        if self.count and Path(path) == self.scene_path:
            if self._asset is None:
                self._asset = self._builder.finish()
            return self._asset
        return super().load(path)

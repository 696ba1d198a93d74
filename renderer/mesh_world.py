"""A mesh scene's assembly made ready for the device: material rows, texture slots and pages, and
the Features it compiles with. The Renderer's world building (renderer/renderer.py, build_world)
uploads the result; `info` reports its device memory.

The scene layer (renderer/scene/mesh_assembly.py) places the primitives and lists the materials in
the order their ids count; here each becomes a row of the material table in that same order, a
model file's texture references become texture slots over the packed pages, and its volume
medium is numbered after the scene's own media.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from renderer.geometry.mesh_data import MeshData
from renderer.materials.table import NO_MEDIUM, MaterialRows
from renderer.scene.description import Scene
from renderer.scene.features import (Features, features_from, scene_grid_media, scene_light_kinds,
                                     scene_light_textures, scene_pixel_filter)
from renderer.scene.mesh_assembly import ModelMaterial, assemble
from renderer.scene.textures import WRAP_CODES, TextureAtlas, pack_atlas


@dataclass
class MeshScene:
    data: MeshData
    rows: MaterialRows
    atlas: TextureAtlas | None
    texture_slots: list  # (rect[+ levels], wrap_s, wrap_t, uv_set, matrix[, nearest]) per slot (slot_arrays)
    volume_media: tuple = ()  # MediumSpec of model files' volumes, numbered after the scene's media
    # The assembly's materials (the scene's, then model files' own) and which image each texture of
    # a scene material reads: what material_rows needs to make the rows again after an edit.
    materials: tuple = ()
    spec_images: dict = field(default_factory=dict)

    def material_uses(self) -> dict:
        return self.rows.uses()

    def features(self, scene: Scene) -> Features:
        """The Features of `scene`, of which this is the assembly (with the scene camera's lens)."""
        uses = {**self.material_uses(), "grid_media": scene_grid_media(scene)}
        return features_from("mesh", uses, scene.environment.kind, scene.camera.aperture,
                             mesh_kinds=self.data.kinds(), energy_compensation=scene.render.energy_compensation,
                             fog=scene.fog.model, vertex_colors=self.data.tri_colors is not None,
                             instances=self.data.has_instances, light_kinds=scene_light_kinds(scene),
                             pixel_filter=scene_pixel_filter(scene),
                             orthographic=scene.camera.projection == "orthographic",
                             light_textures=scene_light_textures(scene),
                             environment_rotated=scene.environment.needs_matrix,
                             flipped_normals=self.data.has_flipped)


def prepare_mesh_scene(scene: Scene, instancing: bool = True) -> MeshScene:
    """The scene assembled (instancing False flattens every instance into world triangles), its
    materials as device rows and its model files' textures as slots over packed pages."""
    assembly = assemble(scene, instancing)
    rows, slots = material_rows(scene, assembly.materials, assembly.spec_images)
    atlas, texture_slots = None, []
    if slots:
        mipmaps = scene.render.texture_filter != "none"
        atlas = pack_atlas(assembly.images, mipmaps=mipmaps)
        # Each slot's atlas row, with its image's mip levels (first row, count) where packed.
        texture_slots = [((*atlas.rects[slot[0]], *atlas.level_span[slot[0]]) if mipmaps else atlas.rects[slot[0]],
                          *slot[1:]) for slot in slots]
    return MeshScene(assembly.data, rows, atlas, texture_slots, assembly.volume_media, assembly.materials,
                     assembly.spec_images)


def with_model_edits(model_materials: tuple, scene: Scene) -> tuple:
    """An assembly's model materials with the scene's edits of them (Scene.model_material_edits)
    made anew from the files' own."""
    edits = dict(scene.model_material_edits)
    return tuple(material.edited(edits.get(i)) for i, material in enumerate(model_materials))


def material_rows(scene: Scene, materials: tuple, spec_images: dict) -> tuple[MaterialRows, list]:
    """The device rows of an assembly's materials, in order, and the texture slots they read
    ((image index, wrap_s, wrap_t, uv_set, matrix[, nearest]) each, numbered as the rows use them)."""
    rows = MaterialRows(scene.medium_names())
    slots: list = []
    for index, material in enumerate(materials):
        if not isinstance(material, ModelMaterial):
            texture_slots = {}
            for role, texture in material.textures.items():
                wrap = WRAP_CODES[texture.wrap]
                slots.append((spec_images[(index, role)], wrap, wrap, 0, np.array(texture.transform, np.float32),
                              texture.nearest))
                texture_slots[role] = len(slots) - 1
            rows.add_spec(material, texture_slots)
            continue

        def texture_id(ref, first_image=material.first_image):
            slots.append((first_image + ref.texture, WRAP_CODES[ref.wrap_s], WRAP_CODES[ref.wrap_t], ref.uv_set,
                          ref.matrix))
            return len(slots) - 1

        medium = NO_MEDIUM if material.medium is None else rows.add_medium(material.medium.name)
        rows.add_pbr(material.pbr, texture_id, medium)
    return rows, slots

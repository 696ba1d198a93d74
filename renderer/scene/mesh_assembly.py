"""A mesh scene's objects, loaded and placed in world space: the flat primitive arrays, the
material rows and the texture atlas the device needs. Numpy only; the Renderer uploads the result.

A mesh a model file draws many times (glTF instancing) is kept once, in its own frame, with its
instances' matrices (MeshData's instance fields), except where the device needs it in the world:
an emissive mesh (light sampling picks points on world-space emitters), a singular placement (no
inverse takes rays into its frame) and a mesh left with a single placement are flattened into
world triangles.
"""
from __future__ import annotations

import os
import warnings
from dataclasses import dataclass

import numpy as np

from renderer.geometry.bezier import bezier_fields
from renderer.geometry.mesh_data import MeshData
from renderer.materials.table import KIND_IDS, NO_MEDIUM, MaterialRows
from renderer.scene.errors import SceneError
from renderer.scene.features import Features, features_from
from renderer.scene.mesh_loader import MeshWarning
from renderer.scene.description import MediumSpec, Scene
from renderer.scene.orientation import rewind_to_normals
from renderer.scene.textures import WRAP_CODES, TextureAtlas, pack_atlas

KIND_NAMES = {v: k for k, v in KIND_IDS.items()}
# An attenuation colour of 0 would absorb infinitely: 1e-4 is gone after one attenuation distance
# to the eye already, and keeps sigma_a finite (9.2 / distance).
MIN_ATTENUATION = 1e-4


@dataclass
class MeshScene:
    data: MeshData
    rows: MaterialRows
    atlas: TextureAtlas | None
    texture_slots: list  # (rect, wrap_s, wrap_t, uv_set, matrix) per texture slot
    volume_media: tuple = ()  # MediumSpec of model files' volumes, numbered after the scene's media

    def material_uses(self) -> dict:
        uses = self.rows.uses()
        uses["kinds"] = {KIND_NAMES[k] for k in uses["kinds"]}
        return uses

    def features(self, scene: Scene) -> Features:
        """The Features of `scene`, of which this is the assembly (with the scene camera's lens)."""
        return features_from("mesh", self.material_uses(), scene.environment.kind, scene.camera.aperture,
                             mesh_kinds=self.data.kinds(), energy_compensation=scene.render.energy_compensation,
                             fog=scene.fog.model, vertex_colors=self.data.tri_colors is not None,
                             instances=self.data.has_instances)


# A placement whose 3x3 part has |det| below this fraction of the product of its column lengths
# flattens its mesh onto (nearly) a plane or a line: it has no usable inverse.
SINGULAR_VOLUME = 1e-9


class _Triangles:
    """Per-corner triangle arrays, appended mesh by mesh (None: the mesh lacks the attribute)."""

    KEYS = ("tris", "normals", "uvs", "uvs1", "tangents", "colors", "tri_mat")

    def __init__(self):
        self.parts = {key: [] for key in self.KEYS}

    @property
    def count(self) -> int:
        return sum(len(t) for t in self.parts["tris"])

    def add(self, positions, indices, normals, uv0, uv1, tangents, colors, matrix, material):
        """Local-frame vertex data placed with `matrix`; per-corner arrays appended."""
        m3 = matrix[:3, :3]
        det = np.linalg.det(m3)
        p = positions.astype(np.float64) @ m3.T + matrix[:3, 3]
        idx = indices
        if det < 0:  # a mirroring transform reverses the winding; keep front faces counter-clockwise
            idx = indices[:, [0, 2, 1]]
        self.parts["tris"].append(p[idx].astype(np.float32))
        if normals is not None:
            # Normals transform with the inverse transpose (which also turns them correctly under
            # a mirroring transform).
            inv_t = np.linalg.inv(m3).T if abs(det) > 1e-30 else m3
            n = normals.astype(np.float64) @ inv_t.T
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
            self.parts["normals"].append(n[idx].astype(np.float32))
        else:
            self.parts["normals"].append(None)
        self.parts["uvs"].append(None if uv0 is None else uv0[idx].astype(np.float32))
        self.parts["uvs1"].append(None if uv1 is None else uv1[idx].astype(np.float32))
        self.parts["colors"].append(None if colors is None else colors[idx].astype(np.float32))
        if tangents is not None:
            t = tangents[:, :3].astype(np.float64) @ m3.T
            t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-30)
            w = tangents[:, 3:4] * np.sign(det if det != 0 else 1.0)
            self.parts["tangents"].append(np.concatenate([t, w], axis=1)[idx].astype(np.float32))
        else:
            self.parts["tangents"].append(None)
        self.parts["tri_mat"].append(np.full(len(idx), material, np.int32))


def _singular(matrices: np.ndarray) -> np.ndarray:
    m3 = matrices[:, :3, :3]
    scale = np.prod(np.linalg.norm(m3, axis=1), axis=1)
    return np.abs(np.linalg.det(m3)) <= SINGULAR_VOLUME * scale


class _Builder:
    def __init__(self, scene: Scene, instancing: bool):
        self.scene = scene
        self.instancing = instancing
        self.rows = MaterialRows(scene.medium_names())
        self.material_ids = {m.name: self.rows.add_spec(m) for m in scene.materials}
        self.images: list[np.ndarray] = []
        self.slots: list = []  # (image index, wrap_s, wrap_t, uv_set, matrix)
        self.volume_media: list[MediumSpec] = []  # model files' absorbing interiors, after the scene's media
        self.parts: dict[str, list] = {"spheres": [], "sphere_mat": [], "quads": [], "quad_mat": [], "discs": [],
                                       "disc_mat": []}
        self.world = _Triangles()  # triangles placed in world space
        self.object = _Triangles()  # instanced meshes, each in its own frame
        self.instanced: list = []  # (first triangle in self.object, count) per instanced mesh
        self.instances: list = []  # (instanced mesh, (N, 3, 4) object-to-world matrices)
        self.beziers: list = []  # (cubic segments, matrix, material, spans, sectors) per object

    def volume_medium(self, material, file) -> int:
        """The medium inside a transmissive glTF material with KHR_materials_volume: absorption
        that leaves `attenuation_color` after `attenuation_distance` (Beer's law, sigma_a =
        -ln(colour) / distance per channel; no scattering), or NO_MEDIUM."""
        colour = np.clip(np.asarray(material.attenuation_color, np.float64), MIN_ATTENUATION, 1.0)
        if (material.transmission_factor <= 0.0 or material.thin_walled
                or not np.isfinite(material.attenuation_distance) or material.attenuation_distance <= 0.0
                or np.all(colour >= 1.0)):
            return NO_MEDIUM
        sigma_a = tuple(float(v) for v in -np.log(colour) / material.attenuation_distance)
        name = f"{os.fspath(file)}#{material.name}"
        self.volume_media.append(MediumSpec(name, sigma_a=sigma_a, sigma_s=(0.0, 0.0, 0.0), g=0.0))
        return self.rows.add_medium(name)

    def material(self, name, where):
        if name not in self.material_ids:
            raise SceneError(self.scene.path, f"{where}: unknown material '{name}'")
        return self.material_ids[name]

    def add_asset(self, obj, index):
        asset = self.scene.model_files.load(obj.file)
        if obj.material is not None:
            mats = [self.material(obj.material, f"objects[{index}]")] * max(1, len(asset.materials))
        else:
            first_image = len(self.images)
            self.images.extend(asset.images)

            def texture_id(ref):
                self.slots.append((first_image + ref.texture, WRAP_CODES[ref.wrap_s], WRAP_CODES[ref.wrap_t],
                                   ref.uv_set, ref.matrix))
                return len(self.slots) - 1

            mats = [self.rows.add_pbr(m, texture_id, self.volume_medium(m, obj.file)) for m in asset.materials]
        matrix = obj.matrix()
        turned = 0
        for mesh in asset.meshes:
            turned += self.add_mesh(self.world, mesh, matrix, mats[mesh.material])
        for inst in asset.instanced:
            material = mats[inst.mesh.material]
            matrices = matrix @ inst.matrices  # the scene object's placement, then the file's
            flat = _singular(matrices)
            if (not self.instancing or max(self.rows.rows[material]["emission"]) > 0.0
                    or np.count_nonzero(~flat) < 2):
                flat[:] = True  # emitters stay where light sampling finds them; one placement is a world mesh
            for k in np.flatnonzero(flat):
                turned += self.add_mesh(self.world, inst.placed(k), matrix, material)
            if not flat.all():
                first = self.object.count
                turned += self.add_mesh(self.object, inst.mesh, np.eye(4), material)
                self.instanced.append((first, self.object.count - first))
                self.instances.append((len(self.instanced) - 1, matrices[~flat, :3, :]))
        if turned:
            warnings.warn(f"{os.fspath(obj.file)}: {turned} triangles wound against their vertex normals were "
                          "turned to face the way the normals do", MeshWarning, stacklevel=2)

    @staticmethod
    def add_mesh(target: _Triangles, mesh, matrix, material) -> int:
        """Adds a TriangleMesh placed with `matrix`; returns how many triangles were rewound."""
        indices, count = rewind_to_normals(mesh.positions, mesh.indices, mesh.normals)
        target.add(mesh.positions, indices, mesh.normals, mesh.uv0, mesh.uv1, mesh.tangents, mesh.colors, matrix,
                   material)
        return count

    def add_object(self, obj, index):
        where = f"objects[{index}]"
        matrix = obj.matrix()
        if obj.kind == "mesh":
            self.add_asset(obj, index)
        elif obj.kind == "generated":
            from renderer.scene.generators import generate

            positions, indices, normals = generate(obj.generator, dict(obj.params))
            self.world.add(positions, indices, normals, None, None, None, None, matrix,
                           self.material(obj.material, where))
        elif obj.kind == "sphere":
            self.parts["spheres"].append([*obj.translate, obj.radius * obj.scale[0]])
            self.parts["sphere_mat"].append(self.material(obj.material, where))
        elif obj.kind == "disc":
            normal = matrix[:3, :3] @ np.array([0.0, 1.0, 0.0])
            normal /= np.linalg.norm(normal)
            self.parts["discs"].append([*obj.translate, *normal, obj.radius * obj.scale[0]])
            self.parts["disc_mat"].append(self.material(obj.material, where))
        elif obj.kind == "quad":
            sx, sz = obj.size
            # Edges chosen so that edge_u x edge_v = +y: the quad faces up before the transform.
            corner = matrix @ np.array([-sx / 2, 0.0, -sz / 2, 1.0])
            edge_u = matrix[:3, :3] @ np.array([0.0, 0.0, sz])
            edge_v = matrix[:3, :3] @ np.array([sx, 0.0, 0.0])
            self.parts["quads"].append([corner[:3], edge_u, edge_v])
            self.parts["quad_mat"].append(self.material(obj.material, where))
        elif obj.kind == "bezier":
            from renderer.geometry.bezier import cubic_segments, profile_problem

            # The loader has checked scene files; scenes built in code are checked here.
            problem = profile_problem(obj.profile, obj.degree)
            if problem:
                raise SceneError(self.scene.path, f"{where}: {problem}")
            self.beziers.append((cubic_segments(obj.profile, obj.degree), matrix,
                                 self.material(obj.material, where), obj.spans, obj.sectors))
        else:
            raise SceneError(self.scene.path, f"{where}: unknown mesh object type '{obj.kind}'")

    def per_corner(self, key, width, missing=0.0):
        """Concatenate a per-corner attribute of the world triangles, then of the instanced meshes,
        or None when no mesh has it (meshes without it get `missing`)."""
        arrays = self.world.parts[key] + self.object.parts[key]
        if not any(a is not None for a in arrays):
            return None
        tris = self.world.parts["tris"] + self.object.parts["tris"]
        return np.concatenate([a if a is not None else np.full((len(t), 3, width), missing, np.float32)
                               for a, t in zip(arrays, tris)])

    def result(self) -> MeshScene:
        p = self.parts
        tris = self.world.parts["tris"] + self.object.parts["tris"]
        materials = self.world.parts["tri_mat"] + self.object.parts["tri_mat"]
        world = self.world.count
        instance_mesh = [np.full(len(m), i, np.int32) for i, m in self.instances]
        # Meshes without normals get zero normals, which the device reads as "use the geometric
        # one"; meshes without colours get white (glTF: COLOR_0 multiplies the base colour).
        data = MeshData(
            tri_vertices=np.concatenate(tris) if tris else np.zeros((0, 3, 3), np.float32),
            tri_normals=self.per_corner("normals", 3), tri_uvs=self.per_corner("uvs", 2),
            tri_uvs1=self.per_corner("uvs1", 2), tri_tangents=self.per_corner("tangents", 4),
            tri_colors=self.per_corner("colors", 4, missing=1.0),
            tri_material=np.concatenate(materials) if materials else np.zeros(0, np.int32),
            spheres=np.array(p["spheres"], np.float32).reshape(-1, 4),
            sphere_material=np.array(p["sphere_mat"], np.int32),
            quads=np.array(p["quads"], np.float32).reshape(-1, 3, 3),
            quad_material=np.array(p["quad_mat"], np.int32),
            discs=np.array(p["discs"], np.float32).reshape(-1, 7),
            disc_material=np.array(p["disc_mat"], np.int32),
            instanced_meshes=np.array([(world + first, n) for first, n in self.instanced], np.int32).reshape(-1, 2),
            instance_mesh=np.concatenate(instance_mesh) if instance_mesh else np.zeros(0, np.int32),
            instance_to_world=(np.concatenate([m for _, m in self.instances]) if self.instances
                               else np.zeros((0, 3, 4))),
            **bezier_fields(self.beziers))
        atlas, slots = None, []
        if self.slots:
            packed = pack_atlas(self.images)
            atlas = packed
            slots = [(packed.rects[img], ws, wt, uv_set, matrix) for img, ws, wt, uv_set, matrix in self.slots]
        return MeshScene(data, self.rows, atlas, slots, tuple(self.volume_media))


def assemble(scene: Scene, instancing: bool = True) -> MeshScene:
    """The scene's device arrays; instancing False flattens every instance into world triangles."""
    builder = _Builder(scene, instancing)
    for i, obj in enumerate(scene.mesh_objects):
        builder.add_object(obj, i)
    result = builder.result()
    if result.data.primitive_count == 0:
        raise SceneError(scene.path, "the scene has no primitives")
    return result

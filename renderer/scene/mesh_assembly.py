"""A mesh scene's objects, loaded and placed in world space, as plain data: the flat primitive
arrays, the materials in the order the device numbers them, and the model files' images.
Numpy only; renderer/mesh_world.py turns the result into the device's material rows and texture
pages.

A mesh a model file draws many times (glTF instancing) is kept once, in its own frame, with its
instances' matrices (MeshData's instance fields), except where the device needs it in the world:
an emissive mesh (light sampling picks points on world-space emitters), a singular placement (no
inverse takes rays into its frame) and a mesh left with a single placement are flattened into
world triangles. Every placement goes through `mesh_model.place_mesh`.
"""
from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field, replace
from typing import Optional, Union

import numpy as np

from renderer.geometry.bezier import bezier_fields, cubic_segments, profile_problem
from renderer.geometry.mesh_data import MeshData
from renderer.scene.description import MaterialSpec, MediumSpec, Scene
from renderer.scene.errors import SceneError
from renderer.scene.generators import generated_mesh
from renderer.scene.mesh_adjustments import adjusted, selected_meshes
from renderer.scene.mesh_attributes import AttributeColoring
from renderer.scene.mesh_model import PbrMaterial, TextureImage, TriangleMesh, place_mesh
from renderer.scene.model_material_edits import edited_pbr
from renderer.scene.model_formats import MeshWarning
from renderer.scene.orientation import rewind_to_normals
from renderer.scene.texture_images import texture_image

# An attenuation colour of 0 would absorb infinitely: 1e-4 is gone after one attenuation distance
# to the eye already, and keeps sigma_a finite (9.2 / distance).
MIN_ATTENUATION = 1e-4
# A placement whose 3x3 part has |det| below this fraction of the product of its column lengths
# flattens its mesh onto (nearly) a plane or a line: it has no usable inverse.
SINGULAR_VOLUME = 1e-9


@dataclass(frozen=True)
class ModelMaterial:
    """A model file's material as one object of the scene uses it: the glTF material, where the
    file's images start in `MeshAssembly.images` (its TextureRefs count from there), and the
    absorbing medium inside it (KHR_materials_volume), or None."""

    pbr: PbrMaterial
    first_image: int
    medium: Optional[MediumSpec] = None
    # the material as the file gives it, where the scene edits it (Scene.model_material_edits)
    file_pbr: Optional[PbrMaterial] = None

    def edited(self, changes) -> "ModelMaterial":
        """This material with the file's factors replaced by `changes` ((PbrMaterial attribute,
        value) pairs; none: the file's own material)."""
        file_pbr = self.file_pbr or self.pbr
        if not changes:
            return self if self.file_pbr is None else replace(self, pbr=file_pbr, file_pbr=None)
        return replace(self, pbr=edited_pbr(file_pbr, changes), file_pbr=file_pbr)


@dataclass
class MeshAssembly:
    """data: the primitives, their material ids indexing `materials`; materials: the scene
    file's materials (all of them, first), then each model object's materials; images: the scene
    file's materials' texture images, then every model object's images, in that order;
    spec_images: which image each texture of a scene-file material reads ((material index, its
    role in MaterialSpec.textures) -> image index); volume_media: the model materials' media, numbered after the scene's own."""

    data: MeshData
    materials: tuple[Union[MaterialSpec, ModelMaterial], ...]
    images: list[TextureImage]
    spec_images: dict = field(default_factory=dict)

    @property
    def volume_media(self) -> tuple[MediumSpec, ...]:
        return tuple(m.medium for m in self.materials if isinstance(m, ModelMaterial) and m.medium is not None)


def volume_medium(material: PbrMaterial, file) -> Optional[MediumSpec]:
    """The medium inside a transmissive glTF material with KHR_materials_volume: absorption that
    leaves `attenuation_color` after `attenuation_distance` (Beer's law, sigma_a = -ln(colour) /
    distance per channel; no scattering), named after the file and the material; or None."""
    colour = np.clip(np.asarray(material.attenuation_color, np.float64), MIN_ATTENUATION, 1.0)
    if (material.transmission_factor <= 0.0 or material.thin_walled
            or not np.isfinite(material.attenuation_distance) or material.attenuation_distance <= 0.0
            or np.all(colour >= 1.0)):
        return None
    sigma_a = tuple(float(v) for v in -np.log(colour) / material.attenuation_distance)
    return MediumSpec(f"{os.fspath(file)}#{material.name}", sigma_a=sigma_a, sigma_s=(0.0, 0.0, 0.0), g=0.0)


def emits(material: Union[MaterialSpec, ModelMaterial]) -> bool:
    emission = material.pbr.emissive_factor if isinstance(material, ModelMaterial) else material.emission
    return max(emission) > 0.0


class _Triangles:
    """Per-corner triangle arrays of placed meshes, appended mesh by mesh (None: the mesh lacks
    the attribute)."""

    KEYS = ("tris", "normals", "uvs", "uvs1", "tangents", "colors", "tri_mat")

    def __init__(self):
        self.parts = {key: [] for key in self.KEYS}

    @property
    def count(self) -> int:
        return sum(len(t) for t in self.parts["tris"])

    def add(self, mesh: TriangleMesh, material: int) -> None:
        idx = mesh.indices
        for key, values in (("tris", mesh.positions), ("normals", mesh.normals), ("uvs", mesh.uv0),
                            ("uvs1", mesh.uv1), ("tangents", mesh.tangents), ("colors", mesh.colors)):
            self.parts[key].append(None if values is None else values[idx].astype(np.float32))
        self.parts["tri_mat"].append(np.full(len(idx), material, np.int32))


def _singular(matrices: np.ndarray) -> np.ndarray:
    m3 = matrices[:, :3, :3]
    scale = np.prod(np.linalg.norm(m3, axis=1), axis=1)
    return np.abs(np.linalg.det(m3)) <= SINGULAR_VOLUME * scale


class _Assembler:
    def __init__(self, scene: Scene, instancing: bool):
        self.scene = scene
        self.instancing = instancing
        self.materials: list = list(scene.materials)
        self.material_ids = {m.name: i for i, m in enumerate(scene.materials)}
        self.model_edits = dict(scene.model_material_edits)
        self.images: list[TextureImage] = []
        self.parts: dict[str, list] = {"spheres": [], "sphere_mat": [], "sphere_frames": [], "sphere_flip": [],
                                       "quads": [], "quad_mat": [], "quad_flip": [], "discs": [], "disc_mat": []}
        self.world = _Triangles()  # triangles placed in world space
        self.object = _Triangles()  # instanced meshes, each in its own frame
        self.instanced: list = []  # (first triangle in self.object, count) per instanced mesh
        self.instances: list = []  # (instanced mesh, (N, 3, 4) object-to-world matrices)
        self.beziers: list = []  # (cubic segments, matrix, material, spans, sectors) per object
        # (scene material index, texture role) -> the image that texture reads
        self.spec_images: dict[tuple[int, str], int] = {}
        self.attribute_colors = AttributeColoring(scene.model_files.ledger)
        # the scene object of the primitives added, by where they went (world and object-space
        # triangles, spheres, quads, discs, Bezier objects): (object index, how many) runs
        self.owners: dict[str, list] = {key: [] for key in self._tallies()}
        for index, material in enumerate(scene.materials):
            for role, texture in material.textures.items():
                self.images.append(texture_image(texture, scene.model_files.ledger))
                self.spec_images[(index, role)] = len(self.images) - 1

    def _tallies(self) -> dict[str, int]:
        return {"world": self.world.count, "object": self.object.count, "spheres": len(self.parts["spheres"]),
                "quads": len(self.parts["quads"]), "discs": len(self.parts["discs"]), "beziers": len(self.beziers)}

    def add_owned(self, obj, index):
        """add_object, noting `index` as the owner of every primitive it adds."""
        before = self._tallies()
        self.add_object(obj, index)
        for key, count in self._tallies().items():
            self.owners[key].append((index, count - before[key]))

    def prim_objects(self, data: MeshData) -> np.ndarray:
        """The owner of each primitive in global id order (MeshData.prim_object)."""
        def owners(key: str) -> np.ndarray:
            runs = np.array(self.owners[key], np.int64).reshape(-1, 2)
            return np.repeat(runs[:, 0], runs[:, 1]).astype(np.int32)

        bezier = owners("beziers")
        patches = (bezier[data.bezier_curve_object[data.bezier_patch_curve]] if len(data.bezier_patches)
                   else np.zeros(0, np.int32))
        return np.concatenate([owners(k) for k in ("world", "object", "spheres", "quads", "discs")] + [patches])

    def material(self, name, where):
        if name not in self.material_ids:
            raise SceneError(self.scene.path, f"{where}: unknown material '{name}'")
        return self.material_ids[name]

    def add_asset(self, obj, index):
        try:
            asset = self.scene.model_files.load(obj.file)
        except SceneError as error:
            if not obj.skip_unreadable:
                raise
            warnings.warn(MeshWarning(f"{error}: the shape is left out"), stacklevel=2)
            return
        if obj.material is not None:
            mats = [self.material(obj.material, f"objects[{index}]")] * max(1, len(asset.materials))
        else:
            first_image = len(self.images)
            self.images.extend(asset.images)
            mats = []
            for m in asset.materials:
                changes = self.model_edits.get(len(self.materials) - len(self.scene.materials))
                self.materials.append(ModelMaterial(m, first_image, volume_medium(m, obj.file)).edited(changes))
                mats.append(len(self.materials) - 1)
        matrix = obj.matrix()
        turned = 0
        meshes = selected_meshes(asset.meshes, obj)
        if not meshes and obj.part is not None:
            raise SceneError(self.scene.path, f"objects[{index}]: {os.fspath(obj.file)} has no mesh '{obj.part}' "
                                              "with triangles")
        attribute = self.materials[mats[0]].base_color_attribute if obj.material is not None else None
        for mesh in meshes:
            mesh = adjusted(mesh, obj)
            if attribute is not None:  # the material's colour from the file's vertex or face attribute
                mesh = self.attribute_colors.colored(mesh, obj.file, attribute)
            turned += self.add_mesh(self.world, mesh, matrix, mats[mesh.material])
        for inst in asset.instanced if obj.part is None else ():
            inst = replace(inst, mesh=adjusted(inst.mesh, obj))
            material = mats[inst.mesh.material]
            matrices = matrix @ inst.matrices  # the scene object's placement, then the file's
            flat = _singular(matrices)
            if not self.instancing or emits(self.materials[material]) or np.count_nonzero(~flat) < 2:
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
    def add_mesh(target: _Triangles, mesh: TriangleMesh, matrix, material) -> int:
        """Adds a TriangleMesh placed with `matrix`; returns how many triangles were rewound."""
        indices, count = rewind_to_normals(mesh.positions, mesh.indices, mesh.normals)
        target.add(place_mesh(replace(mesh, indices=indices), matrix), material)
        return count

    def add_object(self, obj, index):
        where = f"objects[{index}]"
        matrix = obj.matrix()
        if obj.kind == "mesh":
            self.add_asset(obj, index)
        elif obj.kind == "generated":
            self.world.add(place_mesh(adjusted(generated_mesh(obj.generator, dict(obj.params)), obj), matrix),
                           self.material(obj.material, where))
        elif obj.kind == "sphere":
            centre, scale = obj.centre_and_scale()
            self.parts["spheres"].append([*centre, obj.radius * scale])
            self.parts["sphere_mat"].append(self.material(obj.material, where))
            self.parts["sphere_frames"].append((matrix[:3, :3] / np.linalg.norm(matrix[:3, :3], axis=0)).T)
            self.parts["sphere_flip"].append(obj.flip_normals)
        elif obj.kind == "disc":
            normal = matrix[:3, :3] @ np.array([0.0, 1.0, 0.0])
            normal /= np.linalg.norm(normal)
            if obj.flip_normals:  # a disc's normal is data: turned over here, no flag on the device
                normal = -normal
            centre, scale = obj.centre_and_scale()
            self.parts["discs"].append([*centre, *normal, obj.radius * scale])
            self.parts["disc_mat"].append(self.material(obj.material, where))
        elif obj.kind == "quad":
            sx, sz = obj.size
            # Edges chosen so that edge_u x edge_v = +y: the quad faces up before the transform.
            corner = matrix @ np.array([-sx / 2, 0.0, -sz / 2, 1.0])
            edge_u = matrix[:3, :3] @ np.array([0.0, 0.0, sz])
            edge_v = matrix[:3, :3] @ np.array([sx, 0.0, 0.0])
            self.parts["quads"].append([corner[:3], edge_u, edge_v])
            self.parts["quad_mat"].append(self.material(obj.material, where))
            self.parts["quad_flip"].append(obj.flip_normals)
        elif obj.kind == "bezier":
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

    def result(self) -> MeshAssembly:
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
            sphere_frames=np.array(p["sphere_frames"], np.float32).reshape(-1, 3, 3),
            quads=np.array(p["quads"], np.float32).reshape(-1, 3, 3),
            quad_material=np.array(p["quad_mat"], np.int32),
            sphere_flipped=np.array(p["sphere_flip"], bool), quad_flipped=np.array(p["quad_flip"], bool),
            discs=np.array(p["discs"], np.float32).reshape(-1, 7),
            disc_material=np.array(p["disc_mat"], np.int32),
            instanced_meshes=np.array([(world + first, n) for first, n in self.instanced], np.int32).reshape(-1, 2),
            instance_mesh=np.concatenate(instance_mesh) if instance_mesh else np.zeros(0, np.int32),
            instance_to_world=(np.concatenate([m for _, m in self.instances]) if self.instances
                               else np.zeros((0, 3, 4))),
            **bezier_fields(self.beziers))
        model_count = len(self.materials) - len(self.scene.materials)
        beyond = [i for i in self.model_edits if i >= model_count]
        if beyond:
            raise SceneError(self.scene.path, f"model_materials.{beyond[0]}: the scene's model files bring "
                                              f"{model_count} materials" + (f" (0 to {model_count - 1})" if model_count else ""))
        return MeshAssembly(data, tuple(self.materials), self.images, self.spec_images)


def assemble(scene: Scene, instancing: bool = True) -> MeshAssembly:
    """The scene's primitives and materials; instancing False flattens every instance into world
    triangles."""
    assembler = _Assembler(scene, instancing)
    for i, obj in enumerate(scene.mesh_objects):
        assembler.add_owned(obj, i)
    result = assembler.result()
    result.data.prim_object = assembler.prim_objects(result.data)
    if result.data.primitive_count == 0:
        raise SceneError(scene.path, "the scene has no primitives")
    return result

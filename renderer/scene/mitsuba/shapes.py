"""Mitsuba 3 shape plugins made into Lantern's mesh objects (the shape part of scene_builder.py, which
hands each top-level shape here and gives each shape its material).

  obj, ply, serialized   a model file (`MeshObject` kind mesh) with Mitsuba's options: face_normals
                         (flat shading; else the file's normals, or angle-weighted ones where it has
                         none, as Mitsuba computes them), flip_normals, flip_tex_coords (OBJ: on by
                         default, PLY: off; Lantern's readers turn both formats' v over, so the object
                         turns it back where Mitsuba does not), shape_index (serialized)
  sphere, rectangle      Lantern's analytic spheres (texture coordinates in the frame of to_world, as
                         Mitsuba's) and quads: exact, as Mitsuba's, flip_normals (and a mirroring
                         to_world) included
  disk, cube, cylinder   the `disc_fan`, `cube` and `cylinder` generators' meshes (flip_normals): the
                         cube is a mesh in Mitsuba too; the disk and the open tube (p0, p1, radius)
                         are finely tessellated, with exact normals and Mitsuba's (u, v), and take
                         any to_world (an ellipse, as Mitsuba's disk does)
  shapegroup, instance   a group declares shapes and draws nothing; each instance draws every shape of
                         its group placed by the instance's to_world (flattened: each placement is an
                         object of its own)

A shape's material (BSDF, area emitter, interior medium) is the builder's `shape_material`, made once
per shape plugin however many instances draw it.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from renderer.scene.description import MeshObject
from renderer.scene.mitsuba.plugins import Plugin
from renderer.scene.mitsuba.scene_warnings import leave_out
from renderer.scene.model_formats.serialized import shape_count, shape_name

MESH_FILE_TYPES = ("obj", "ply", "serialized")
FLIP_TEX_COORDS = {"obj": True, "ply": False}  # Mitsuba's defaults (serialized has no such parameter)
# Lantern's local frame for quads lies in xz and faces +y; Mitsuba's rectangle lies in xy and faces
# +z. This rotation takes local z to x, x to y and y (the normal) to z, so a quad's edge parameters
# (along its local z, then x) are the rectangle's texture coordinates (u, v).
XZ_TO_XY = np.array([[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
# The cylinder and disc_fan generators stand on the local y axis, their angle running from +x towards
# -z; Mitsuba's cylinder and disk stand on z, their angle from +x towards +y. This rotation takes the
# one to the other.
Y_AXIS_TO_Z = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
# Quads around a Mitsuba cylinder: its silhouette lies within 5e-6 of the radius of the true one,
# far below a pixel at any size a test scene shows it.
CYLINDER_SECTORS = 1024


class ShapeReader:
    def __init__(self, builder):
        self.builder = builder
        self.material_of: dict[int, str] = {}  # id(shape plugin) -> its material's name
        self.left_out: set[int] = set()  # shapes warned about once, however many instances draw them

    def read(self, shape: Plugin, outer: np.ndarray | None = None) -> None:
        """Adds the objects of a shape placed by `outer` (an instance's to_world) then its own to_world."""
        self.builder.visit(shape)
        placement = shape.transform() if outer is None else outer @ shape.transform()
        t = shape.type
        if t == "shapegroup":  # a declaration: its shapes are drawn where instances place them
            shape.objects("shape")
            return
        if t == "instance":
            self.instance(shape, placement)
            return
        if t not in MESH_FILE_TYPES + ("sphere", "rectangle", "disk", "cube", "cylinder"):
            if id(shape) not in self.left_out:
                self.left_out.add(id(shape))
                leave_out(shape, "this shape type is not supported yet and is left out")
            return
        material = self.material(shape)
        if t not in MESH_FILE_TYPES and self.attribute_coloured(material):
            raise shape.error("a mesh_attribute texture needs a mesh file's vertex or face attributes "
                              f"(obj, ply, serialized), not a {t}")
        if t in MESH_FILE_TYPES:
            self.add(self.mesh_file(shape, material), placement, shape)
        elif t == "sphere":
            centre = np.array(shape.get("center", (0.0, 0.0, 0.0)), np.float64)
            radius = shape.number("radius", 1.0)
            scales = np.linalg.norm(placement[:3, :3], axis=0)
            if not np.allclose(scales, scales[0], rtol=1e-5):
                raise shape.error("a sphere's to_world must scale uniformly")
            self.add(MeshObject(kind="sphere", radius=radius, material=material,
                                flip_normals=analytic_flip(shape, placement)), placement @ _translation(centre), shape)
        elif t == "rectangle":
            self.add(MeshObject(kind="quad", size=(2.0, 2.0), material=material,
                                flip_normals=analytic_flip(shape, placement)), placement @ XZ_TO_XY, shape)
        elif t == "disk":
            self.add(self.generated(shape, "disc_fan", material), placement @ Y_AXIS_TO_Z, shape)
        elif t == "cube":
            self.add(self.generated(shape, "cube", material), placement, shape)
        else:
            self.add(self.generated(shape, "cylinder", material, (("sectors", CYLINDER_SECTORS),)),
                     placement @ cylinder_frame(shape) @ Y_AXIS_TO_Z, shape)

    def generated(self, shape: Plugin, generator: str, material: str, params=()) -> MeshObject:
        return MeshObject(kind="generated", generator=generator, params=params, material=material,
                          flip_normals=_flag(shape, "flip_normals", False))

    def instance(self, shape: Plugin, placement: np.ndarray) -> None:
        groups = shape.objects("shape")
        if len(groups) != 1 or groups[0].type != "shapegroup":
            raise shape.error("needs one <shapegroup> (a <ref> to one)")
        group = self.builder.visit(groups[0])
        for member in group.objects("shape"):
            self.read(member, placement)

    def material(self, shape: Plugin) -> str:
        if id(shape) not in self.material_of:
            self.material_of[id(shape)] = self.builder.shape_material(shape)
        return self.material_of[id(shape)]

    def attribute_coloured(self, material: str) -> bool:
        """Whether the named material takes its colour from a mesh attribute."""
        return any(m.name == material and m.base_color_attribute is not None for m in self.builder.materials)

    def mesh_file(self, shape: Plugin, material: str) -> MeshObject:
        name = shape.text("filename")
        if name is None:
            raise shape.error("needs a filename")
        file = self.builder.find(shape, name)
        part = None
        if shape.type == "serialized":
            index = shape.integer("shape_index", 0)
            count = shape_count(file)
            if not 0 <= index < count:
                raise shape.error(f"shape_index {index} is out of range: {name} holds {count} "
                                  f"shape{'s' if count > 1 else ''} (0 to {count - 1})")
            part = shape_name(index)
        flip_v = shape.type in FLIP_TEX_COORDS and not _flag(shape, "flip_tex_coords", FLIP_TEX_COORDS[shape.type])
        # Mitsuba shades with a mesh's vertex colours only through a mesh_attribute texture.
        return MeshObject(kind="mesh", file=file, material=material, part=part, flip_v=flip_v, vertex_colors=False,
                          normals="flat" if _flag(shape, "face_normals", False) else "smooth",
                          flip_normals=_flag(shape, "flip_normals", False))

    def add(self, obj: MeshObject, matrix: np.ndarray, shape: Plugin) -> None:
        if not np.all(np.isfinite(matrix)) or abs(np.linalg.det(matrix[:3, :3])) < 1e-30:
            raise shape.error("its to_world is singular")
        self.builder.objects.append(replace(obj, to_world=tuple(tuple(float(x) for x in row) for row in matrix)))


def cylinder_frame(shape: Plugin) -> np.ndarray:
    """Mitsuba's cylinder's own placement: the unit tube on z in [0, 1] moved to stand from p0 to p1
    with its radius, turned about its axis by the frame Mitsuba builds around the axis (Duff et al.
    2017, "Building an orthonormal basis, revisited"), on which its u = 0 line depends."""
    p0 = np.array(_point(shape, "p0", (0.0, 0.0, 0.0)), np.float64)
    p1 = np.array(_point(shape, "p1", (0.0, 0.0, 1.0)), np.float64)
    radius = shape.number("radius", 1.0)
    length = float(np.linalg.norm(p1 - p0))
    if not radius > 0.0 or not length > 0.0:
        raise shape.error(f"a cylinder needs a positive radius and distinct p0 and p1 (radius {radius:g}, "
                          f"length {length:g})")
    n = (p1 - p0) / length
    sign = math.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    s = np.array([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]])
    t = np.array([b, sign + n[1] * n[1] * a, -n[1]])
    frame = np.eye(4)
    frame[:3, 0], frame[:3, 1], frame[:3, 2], frame[:3, 3] = radius * s, radius * t, length * n, p0
    return frame


def analytic_flip(shape: Plugin, placement: np.ndarray) -> bool:
    """Whether Lantern's sphere or quad must turn its normal over to be Mitsuba's shape: flip_normals,
    exclusive-or a to_world that mirrors. Under a mirror Mitsuba's sphere points its normals inwards
    (its to_world decomposes with a negative scale) where Lantern's point outwards, and Mitsuba's
    rectangle keeps to_world's transformed normal where Lantern's quad takes edge u x edge v, which
    a mirror turns over."""
    return _flag(shape, "flip_normals", False) != bool(np.linalg.det(placement[:3, :3]) < 0.0)


def _flag(plugin: Plugin, name: str, default: bool) -> bool:
    value = plugin.get(name, default)
    if not isinstance(value, bool):
        raise plugin.error(f"'{name}' must be a <boolean>")
    return value


def _point(plugin: Plugin, name: str, default) -> tuple:
    value = plugin.get(name, default)
    if not (isinstance(value, tuple) and len(value) == 3):
        raise plugin.error(f"'{name}' must be a <point>")
    return value


def _translation(offset) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = offset
    return m

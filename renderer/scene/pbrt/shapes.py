"""pbrt-v4 shapes made into Lantern's mesh objects.

  trianglemesh, bilinearmesh   inline meshes (inline_meshes.py); a bilinear patch as two triangles
  plymesh                      the PLY file (.ply.gz decompressed), a missing one left out with a warning
  sphere                       Lantern's analytic sphere (an icosphere under a non-uniform scale)
  disk, cylinder               the disc_fan and cylinder generators' meshes
  loopsubdiv                   its control mesh, unsubdivided (a warning)
A shape's front is pbrt's: its normal flipped by ReverseOrientation (a sphere's also by a mirroring
transform, as in pbrt, since Lantern's sphere keeps pointing outwards under one).
"""
from __future__ import annotations

import numpy as np

from renderer.scene.description import MeshObject
from renderer.scene.errors import SceneError
from renderer.scene.pbrt.directives import Directive
from renderer.scene.pbrt.parameters import resolve
from renderer.scene.pbrt.scene_warnings import warn, warn_unused
from renderer.scene.references import missing_file_problem

# The cylinder and disc_fan generators stand on local y; pbrt's disk and cylinder on z.
Y_AXIS_TO_Z = np.array([[1.0, 0, 0, 0], [0, 0, -1.0, 0], [0, 1.0, 0, 0], [0, 0, 0, 1.0]])
SECTORS = 1024
ICOSPHERE_SUBDIVISIONS = 5


def shape_objects(d: Directive, material: str, files) -> list[tuple[MeshObject, np.ndarray]]:
    """The mesh objects of one Shape directive, each with its frame within the shape's (the caller
    places the shape); [] where it is left out (with a warning)."""
    t, p = d.type, d.params
    flip = d.reverse
    objects = []
    if t in ("trianglemesh", "loopsubdiv"):
        if t == "loopsubdiv":
            warn(d, "rendered as its control mesh, unsubdivided")
            p.find("levels")
        points = p.tuples("P", ("point3", "point"), 3)
        if not points:
            raise d.error("needs \"point3 P\"")
        indices = p.integers("indices")
        if indices is None:
            if len(points) != 3:
                raise d.error("needs \"integer indices\" (only a single triangle may leave them out)")
            indices = [0, 1, 2]
        _check_indices(d, indices, len(points), 3)
        normals = p.tuples("N", ("normal", "normal3"), 3)
        uv = p.tuples("uv", ("point2", "float"), 2) or p.tuples("st", ("point2", "float"), 2)
        for name, values in (("N", normals), ("uv", uv)):
            if values is not None and len(values) != len(points):
                raise d.error(f"'{name}' has {len(values)} entries for {len(points)} points")
        part = files.add(np.array(points), np.array(indices).reshape(-1, 3), normals, uv)
        objects.append(MeshObject(kind="mesh", file=files.scene_path, part=part, material=material,
                                  flip_normals=flip, vertex_colors=False))
    elif t == "bilinearmesh":
        points = p.tuples("P", ("point3", "point"), 3)
        if not points:
            raise d.error("needs \"point3 P\"")
        indices = p.integers("indices") or ([0, 1, 2, 3] if len(points) == 4 else None)
        if indices is None:
            raise d.error("needs \"integer indices\" (4 per patch)")
        _check_indices(d, indices, len(points), 4)
        quads = np.array(indices).reshape(-1, 4)  # p00, p10, p01, p11
        triangles = np.concatenate([quads[:, [0, 1, 3]], quads[:, [0, 3, 2]]])
        uv = p.tuples("uv", ("point2",), 2)
        part = files.add(np.array(points), triangles, None, uv)
        objects.append(MeshObject(kind="mesh", file=files.scene_path, part=part, material=material,
                                  flip_normals=flip, vertex_colors=False))
    elif t == "plymesh":
        name = p.string("filename")
        if name is None:
            raise d.error("needs a \"string filename\"")
        path = resolve(p.find("filename").token, name)
        if not path.is_file():
            warn(d, f"{name}: {missing_file_problem(path)} (looked for {path}): the shape is left out")
        elif path.name.lower().endswith(".gz"):
            try:
                part = files.add_gzipped_ply(path)
            except (OSError, ValueError, EOFError) as e:
                raise SceneError(path, f"cannot read the compressed PLY file: {e}") from None
            objects.append(MeshObject(kind="mesh", file=files.scene_path, part=part, material=material,
                                      flip_normals=flip, vertex_colors=False))
        else:
            objects.append(MeshObject(kind="mesh", file=path, material=material, flip_normals=flip,
                                      vertex_colors=False, skip_unreadable=True))
    elif t == "sphere":
        radius = p.float("radius", 1.0)
        zmin, zmax, phimax = p.float("zmin", -radius), p.float("zmax", radius), p.float("phimax", 360.0)
        if zmin > -radius or zmax < radius or phimax < 360.0:
            warn(d, "zmin, zmax and phimax cutting a sphere are not supported: the whole sphere is drawn")
        if radius <= 0:
            raise d.error(f"radius {radius:g} is not positive")
        scales = np.linalg.norm(d.ctm[:3, :3], axis=0)
        mirrored = bool(np.linalg.det(d.ctm[:3, :3]) < 0)
        if np.allclose(scales, scales[0], rtol=1e-5):
            objects.append(MeshObject(kind="sphere", radius=radius, material=material, flip_normals=flip != mirrored))
        else:  # Lantern's analytic sphere takes a uniform scale; an ellipsoid becomes a fine mesh
            objects.append(MeshObject(kind="generated", generator="icosphere", material=material, flip_normals=flip,
                                      params=(("radius", radius), ("subdivisions", ICOSPHERE_SUBDIVISIONS))))
    elif t == "disk":
        radius, height = p.float("radius", 1.0), p.float("height", 0.0)
        if p.float("innerradius", 0.0) > 0.0 or p.float("phimax", 360.0) < 360.0:
            warn(d, "innerradius and phimax are not supported: the whole disk is drawn")
        if radius <= 0:
            raise d.error(f"radius {radius:g} is not positive")
        frame = np.eye(4)
        frame[2, 3] = height
        objects.append((MeshObject(kind="generated", generator="disc_fan", material=material, flip_normals=flip,
                                   params=(("radius", radius), ("sectors", SECTORS))), frame @ Y_AXIS_TO_Z))
    elif t == "cylinder":
        radius, zmin, zmax = p.float("radius", 1.0), p.float("zmin", -1.0), p.float("zmax", 1.0)
        if p.float("phimax", 360.0) < 360.0:
            warn(d, "phimax is not supported: the whole cylinder is drawn")
        if radius <= 0 or zmax <= zmin:
            raise d.error("a cylinder needs a positive radius and zmax above zmin")
        frame = np.diag([1.0, 1.0, zmax - zmin, 1.0])
        frame[2, 3] = zmin
        objects.append((MeshObject(kind="generated", generator="cylinder", material=material, flip_normals=flip,
                                   params=(("radius", radius), ("height", 1.0), ("sectors", SECTORS))),
                        frame @ Y_AXIS_TO_Z))
    else:
        for param in p.params:
            param.used = True
        warn(d, f"the {t} shape is not supported: left out")
        return []
    p.find("alpha")  # (the material's opacity: scene_builder.place)
    warn_unused(d)
    return [o if isinstance(o, tuple) else (o, np.eye(4)) for o in objects]


def _check_indices(d: Directive, indices, count: int, per: int) -> None:
    if len(indices) % per:
        raise d.error(f"'indices' holds {len(indices)} numbers, not a multiple of {per}")
    if indices and (min(indices) < 0 or max(indices) >= count):
        raise d.error(f"'indices' refers to a point outside the {count} given")


def light_areas(d: Directive, obj: MeshObject, matrix: np.ndarray, files) -> list[float]:
    """The areas of the lights pbrt-v4 makes of a placed shape under an area light (its `power`
    divides by them): one per triangle of a mesh, one per bilinear patch, one for a sphere, disk
    or cylinder."""
    if obj.kind == "sphere":
        return [4.0 * np.pi * (obj.radius * float(np.linalg.norm(matrix[:3, 0]))) ** 2]
    if obj.kind == "generated":
        from renderer.scene.generators import generate

        positions, indices, _ = generate(obj.generator, dict(obj.params))
        meshes = [(positions, indices)]
    else:
        asset = files.load(obj.file)
        meshes = [(m.positions, m.indices) for m in asset.meshes if obj.part is None or m.name == obj.part]
    areas = []
    for positions, indices in meshes:
        p = np.asarray(positions, np.float64) @ matrix[:3, :3].T + matrix[:3, 3]
        t = p[np.asarray(indices).reshape(-1, 3)]
        areas.append(0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1))
    areas = np.concatenate(areas) if areas else np.zeros(0)
    if obj.kind == "generated":
        return [float(areas.sum())]
    if d.type == "bilinearmesh":  # its patches' two triangles: the first halves, then the second
        half = len(areas) // 2
        return (areas[:half] + areas[half:]).tolist()
    return areas.tolist()

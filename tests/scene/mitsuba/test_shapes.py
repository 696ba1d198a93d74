"""Mitsuba 3 shapes (renderer/scene/mitsuba/shapes.py) as Lantern draws them: hit points and texture
coordinates of the cube, disk, sphere and cylinder against Mitsuba's own (the EXPECTED values were
computed with Mitsuba 3.9.1's ray_intersect on the same shapes), serialized files and shape_index,
the mesh files' options (face_normals, flip_normals, flip_tex_coords), shape groups and instances."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.mesh_assembly import assemble
from tests.geometry.mesh_helpers import SurfaceProbe, geometry_from
from tests.scene.mitsuba.test_scene_builder import load
from tests.scene.serialized_writer import SQUARE_UVS, TRIANGLE_SHAPE, square, write_serialized

# Per shape: its XML, then rays (origin, direction) with the hit point and (u, v) Mitsuba reports.
EXPECTED = {
    "cube": ('<shape type="cube"/>', [
        ((0.5, -0.25, 5), (0, 0, -1), (0.5, -0.25, 1), (0.375, 0.75)),
        ((0.5, -0.25, -5), (0, 0, 1), (0.5, -0.25, -1), (0.625, 0.75)),
        ((5, 0.3, 0.6), (-1, 0, 0), (1, 0.3, 0.6), (0.65, 0.2)),
        ((-5, 0.3, 0.6), (1, 0, 0), (-1, 0.3, 0.6), (0.65, 0.8)),
        ((0.2, 5, -0.7), (0, -1, 0), (0.2, 1, -0.7), (0.4, 0.85)),
        ((0.2, -5, -0.7), (0, 1, 0), (0.2, -1, -0.7), (0.15, 0.6))]),
    "elliptical disk": ('''<shape type="disk"><transform name="to_world"><scale x="2" y="0.5"/>
            <rotate z="1" angle="30"/><translate z="1"/></transform></shape>''', [
        ((0.5, 0.2, 5), (0, 0, -1), (0.5, 0.2, 1), (0.307596, 0.916791)),
        ((-1.0, -0.4, 5), (0, 0, -1), (-1.0, -0.4, 1), (0.615193, 0.416791))]),
    "turned sphere": ('''<shape type="sphere"><transform name="to_world"><scale value="2"/>
            <rotate x="0.6" y="0.8" angle="70"/><translate x="1" y="2" z="3"/></transform></shape>''', [
        ((1.5, 2.2, 10), (0, 0, -1), (1.5, 2.2, 4.926136), (0.355858, 0.34751)),
        ((1, 12, 3.5), (0, -1, 0), (1, 3.936492, 3.5), (0.228806, 0.652297)),
        ((-10, 1.5, 2.5), (1, 0, 0), (-0.870829, 1.5, 2.5), (0.653911, 0.724291))]),
    "cylinder": ('''<shape type="cylinder"><point name="p0" value="0, 0, 0"/><point name="p1" value="1, 1, 1"/>
            <float name="radius" value="0.5"/></shape>''', [
        ((5, 0, 0.3), (-1, 0, 0), (0.704527, 0, 0.3), (0.8886, 0.334842)),
        ((0, 5, 0.7), (0, -1, 0), (0, 0.436604, 0.7), (0.519083, 0.378868)),
        ((-5, 0.001, 0.5), (1, 0, 0), (-0.183377, 0.001, 0.5), (0.583015, 0.105874)),
        ((0.5, 0.5, 5), (0, 0, -1), (0.5, 0.5, 1.11237), (0.625, 0.704124))]),
}
# Tessellated shapes (the disk's fan, the cylinder's tube) stray from the round surface by about
# 5e-6 of their size; the sphere is exact, the cube a mesh in Mitsuba too.
POINT_TOLERANCE, UV_TOLERANCE = 1e-4, 1e-3


def probe(scene, rays):
    origins = np.array([r[0] for r in rays], np.float64)
    directions = np.array([r[1] for r in rays], np.float64)
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    return SurfaceProbe(geometry_from(assemble(scene).data)).shoot(origins, directions)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_hits_and_texture_coordinates_are_mitsubas(tmp_path, name):
    xml, rays = EXPECTED[name]
    out = probe(load(tmp_path, xml)[0], rays)
    assert (out[:, SurfaceProbe.HIT] == 1).all()
    np.testing.assert_allclose(out[:, SurfaceProbe.P], [r[2] for r in rays], atol=POINT_TOLERANCE)
    np.testing.assert_allclose(out[:, SurfaceProbe.UV], [r[3] for r in rays], atol=UV_TOLERANCE)


def test_the_cylinder_is_an_open_tube_facing_out_unless_flipped(tmp_path):
    rays = [((0.0, 0.0, 5.0), (0.0, 0.0, -1.0)), ((5.0, 0.0, 0.5), (-1.0, 0.0, 0.0))]
    out = probe(load(tmp_path, '<shape type="cylinder"/>')[0], rays)
    assert out[0, SurfaceProbe.HIT] == 0  # down the axis: no caps
    # (the facet a ray meets leans by up to pi / 1024 from the round surface's normal)
    assert out[1, SurfaceProbe.FRONT] == 1 and out[1, SurfaceProbe.N_GEO][0] == pytest.approx(1.0, abs=1e-5)
    flipped = probe(load(tmp_path, '<shape type="cylinder"><boolean name="flip_normals" value="true"/></shape>')[0],
                    rays)
    assert flipped[1, SurfaceProbe.FRONT] == 0 and flipped[1, SurfaceProbe.N_GEO][0] == pytest.approx(-1, abs=1e-5)


def test_serialized_shape_index_picks_one_shape(tmp_path):
    write_serialized(tmp_path / "two.serialized", [square(), TRIANGLE_SHAPE])
    scene, _ = load(tmp_path, '''<shape type="serialized"><string name="filename" value="two.serialized"/>
        <integer name="shape_index" value="1"/></shape>''')
    tris = assemble(scene).data.tri_vertices
    np.testing.assert_array_equal(tris, TRIANGLE_SHAPE.positions[TRIANGLE_SHAPE.indices])
    scene, _ = load(tmp_path, '<shape type="serialized"><string name="filename" value="two.serialized"/></shape>')
    data = assemble(scene).data
    assert len(data.tri_vertices) == 2  # shape 0, the square, with its texture coordinates as stored
    np.testing.assert_array_equal(data.tri_uvs, SQUARE_UVS[square().indices])


@pytest.mark.parametrize("index, problem", [(2, r"shape_index 2 is out of range: two.serialized holds 2 shapes "
                                                  r"\(0 to 1\)"),
                                            (-1, r"shape_index -1 is out of range")])
def test_a_shape_index_out_of_range_is_one_line(tmp_path, index, problem):
    write_serialized(tmp_path / "two.serialized", [square(), TRIANGLE_SHAPE])
    with pytest.raises(SceneError, match=problem) as excinfo:
        load(tmp_path, f'''<shape type="serialized"><string name="filename" value="two.serialized"/>
            <integer name="shape_index" value="{index}"/></shape>''')
    message = str(excinfo.value)
    assert "\n" not in message and message.startswith(f"{tmp_path / 's.xml'}: line 2: <shape type=\"serialized\">")


def test_a_bad_serialized_file_is_one_line_naming_it(tmp_path):
    (tmp_path / "bad.serialized").write_bytes(b"\x00\x01\x02\x03 not a mesh")
    with pytest.raises(SceneError, match=r"bad.serialized: the file: not a Mitsuba serialized mesh") as excinfo:
        load(tmp_path, '<shape type="serialized"><string name="filename" value="bad.serialized"/></shape>')
    assert "\n" not in str(excinfo.value)


def mesh_shape(options: str, kind: str = "serialized") -> str:
    return f'<shape type="{kind}"><string name="filename" value="m.{kind}"/>{options}</shape>'


def test_mesh_file_options(tmp_path):
    write_serialized(tmp_path / "m.serialized", [square()])
    plain = assemble(load(tmp_path, mesh_shape(""))[0]).data
    np.testing.assert_allclose(plain.tri_normals, np.tile((0, 0, 1), (2, 3, 1)))
    faceted = assemble(load(tmp_path, mesh_shape('<boolean name="face_normals" value="true"/>'))[0]).data
    assert faceted.tri_normals is None  # shaded with the geometric normal
    flipped = assemble(load(tmp_path, mesh_shape('<boolean name="flip_normals" value="true"/>'))[0]).data
    np.testing.assert_allclose(flipped.tri_normals, np.tile((0, 0, -1), (2, 3, 1)))
    tris = flipped.tri_vertices.astype(np.float64)
    winding = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    assert (winding[:, 2] < 0).all()  # the front side (emitters', media's) turned over with them
    with pytest.raises(SceneError, match="'flip_normals' must be a <boolean>"):
        load(tmp_path, mesh_shape('<integer name="flip_normals" value="1"/>'))


def test_texture_coordinates_of_obj_and_ply_follow_flip_tex_coords(tmp_path):
    """Mitsuba flips OBJ texture coordinates (v -> 1 - v) unless told not to and keeps PLY's as
    stored unless told to; Lantern's readers flip both, so the object turns them back where Mitsuba
    does not."""
    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25 0.125\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n")
    (tmp_path / "m.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                    "property float z\nproperty float u\nproperty float v\nelement face 1\n"
                                    "property list uchar int vertex_indices\nend_header\n"
                                    "0 0 0 0.25 0.125\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n")

    def first_uv(kind, options=""):
        return tuple(assemble(load(tmp_path, mesh_shape(options, kind))[0]).data.tri_uvs[0, 0])

    flip = '<boolean name="flip_tex_coords" value="{}"/>'
    assert first_uv("obj") == (0.25, 0.875) and first_uv("obj", flip.format("false")) == (0.25, 0.125)
    assert first_uv("ply") == (0.25, 0.125) and first_uv("ply", flip.format("true")) == (0.25, 0.875)


def test_smooth_normals_where_a_file_has_none(tmp_path):
    """Mitsuba gives a mesh without normals angle-weighted vertex normals: here a vertex shared by a
    triangle in z = 0 and a square in x = 0, each with a right angle at it (weighted by their
    areas, 1/2 and 1, the normal would lean towards x)."""
    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0 1 1\nf 1 2 3\nf 1 3 5 4\n")
    data = assemble(load(tmp_path, mesh_shape("", "obj"))[0]).data
    corner = data.tri_normals[0, 0]  # vertex 1 of the first face
    expected = np.array([0.0, 0.0, 1.0]) * np.pi / 2 + np.array([1.0, 0.0, 0.0]) * np.pi / 2
    np.testing.assert_allclose(corner, expected / np.linalg.norm(expected), atol=1e-6)


GROUP = '''<shape type="shapegroup" id="g">
    <shape type="sphere"><float name="radius" value="0.5"/><bsdf type="diffuse"/></shape>
    <shape type="hair"/>
</shape>'''


def instance(translate: str) -> str:
    return (f'<shape type="instance"><ref id="g"/><transform name="to_world"><translate {translate}/>'
            '</transform></shape>')


def test_instances_draw_their_group_where_they_are_placed(tmp_path):
    scene, messages = load(tmp_path, GROUP + instance('x="2"') + instance('y="-3"'), expect_warnings=1)
    assert "<shape type=\"hair\">: this shape type is not supported" in messages[0]  # once for both instances
    data = assemble(scene).data
    np.testing.assert_allclose(data.spheres, [(2, 0, 0, 0.5), (0, -3, 0, 0.5)])
    assert len(scene.materials) == 1 and (data.sphere_material == 0).all()  # one material, drawn twice


def test_a_group_alone_draws_nothing_and_an_instance_needs_one(tmp_path):
    with pytest.raises(SceneError, match="nothing Lantern can render"):
        load(tmp_path, GROUP, expect_warnings=None)
    with pytest.raises(SceneError, match=r"line 2: <shape type=\"instance\">: needs one <shapegroup>"):
        load(tmp_path, '<shape type="instance"><shape type="sphere"/></shape>')


@pytest.mark.parametrize("shape", ["sphere", "rectangle"])
def test_flip_normals_and_a_mirror_turn_analytic_shapes_over_as_mitsubas(tmp_path, shape):
    """Rays from +z onto the sphere's top and the rectangle (facing +z, Mitsuba's way): flip_normals
    turns the normal over; a mirroring to_world turns Mitsuba's sphere inwards (and a flipped one
    back out) and keeps its rectangle's transformed normal (+z under a mirror of x, where Lantern's
    quad, edge u x edge v, would turn); flip_normals keeps texture coordinates."""
    rays = [((0.2, 0.1, 5.0), (0.0, 0.0, -1.0))]
    mirror = '<transform name="to_world"><scale x="-1"/></transform>'

    def hit(options):
        scene = load(tmp_path, f'<shape type="{shape}">{options}<bsdf type="diffuse"/></shape>')[0]
        return probe(scene, rays)[0]
    plain = hit("")
    assert plain[SurfaceProbe.FRONT] == 1 and plain[SurfaceProbe.N_GEO][2] > 0.9
    flip = '<boolean name="flip_normals" value="true"/>'
    for options, turned in (("", False), (flip, True), (mirror, shape == "sphere"), (flip + mirror, shape != "sphere")):
        out = hit(options)
        assert out[SurfaceProbe.FRONT] == (0 if turned else 1), options
        np.testing.assert_allclose(out[SurfaceProbe.N_GEO], -plain[SurfaceProbe.N_GEO] if turned
                                   else plain[SurfaceProbe.N_GEO], atol=1e-6)
        if not options.endswith(mirror):
            np.testing.assert_array_equal(out[SurfaceProbe.UV], plain[SurfaceProbe.UV])
    with pytest.raises(SceneError, match="'flip_normals' must be a <boolean>"):
        load(tmp_path, f'<shape type="{shape}"><integer name="flip_normals" value="1"/></shape>')

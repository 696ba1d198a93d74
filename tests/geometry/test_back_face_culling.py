"""Back-face culling of glTF files (doubleSided: false) under mirroring transforms, ray by ray.

glTF makes the determinant of a node's global transform decide the winding: where it is negative
the front faces are clockwise, so a mirrored quad keeps its front on the side its transformed
normal points to (the loader reverses the winding of a mirrored world mesh; a mirrored instance
is culled in its own frame). Rays from either side of a row of quads (plain, mirrored in and
through their plane, mirrored twice, double-sided, and an instanced pair of which one is mirrored)
must meet a single-sided quad from its front only, pass through it from behind, and see its
geometric normal on its front side. The same holds with the whole file mirrored by the scene
object, under binary and wide traversals with scalar and packet leaves, with instances kept or
flattened, and with or without vertex normals (without them the winding alone decides: with them,
triangles wound against their normals are rewound, renderer/scene/orientation.py, which would hide
a wrong winding). Exact checks: no randomness is involved."""
import numpy as np
import pytest

from renderer.renderer import MeshOptions, Renderer
from renderer.scene.description import CameraSpec, EnvironmentSpec, MeshObject, RenderSettings, Scene
from tests.geometry.mesh_helpers import SurfaceProbe
from tests.scene.model_file_helpers import write_quads_gltf

# (name, translation, scale, parent scale, double-sided, one shared mesh, the z of the front's side)
QUADS = (
    ("plain", (-4.5, 0.0, 0.0), (1, 1, 1), None, False, False, 1),
    ("mirrored_in_plane", (-3.0, 0.0, 0.0), (-1, 1, 1), None, False, False, 1),
    ("mirrored_through_plane", (-1.5, 0.0, 0.0), (1, 1, -1), None, False, False, -1),
    ("mirrored_twice", (0.0, 0.0, 0.0), (1, 1, -1), (-1, 1, 1), False, False, -1),  # a half turn about y
    ("double_sided", (1.5, 0.0, 0.0), (1, 1, 1), None, True, False, 0),
    ("instance", (3.0, 0.0, 0.0), (1, 1, 1), None, False, True, 1),
    ("mirrored_instance", (4.5, 0.0, 0.0), (1, 1, -1), None, False, True, -1),
)
SIDES = (1, -1)  # rays from +z, then from -z


def quads_file(tmp_path, normals=True):
    return write_quads_gltf(tmp_path / "quads.gltf", [q[:6] for q in QUADS], normals)


def geometry(path, options, object_scale=(1.0, 1.0, 1.0)):
    scene = Scene(name="culling", path=None, geometry="mesh", camera=CameraSpec(),
                  render=RenderSettings(width=8, height=8), materials=(),
                  environment=EnvironmentSpec(kind="constant", color=(1.0, 1.0, 1.0)),
                  mesh_objects=(MeshObject(kind="mesh", file=path, scale=object_scale),))
    return Renderer(scene, mesh_options=options)


def rays():
    """One ray per (side, quad), off the quads' diagonals, straight at it from 5 m away."""
    origins = np.array([[q[1][0] + 0.1, 0.13, 5.0 * side] for side in SIDES for q in QUADS], np.float32)
    directions = np.array([[0.0, 0.0, -side] for side in SIDES for _ in QUADS], np.float32)
    return origins, directions


@pytest.mark.parametrize("normals", [False, True], ids=["winding", "normals"])
@pytest.mark.parametrize("object_mirrored", [False, True], ids=["file", "file_mirrored"])
@pytest.mark.parametrize("options", [MeshOptions(traversal="wide8", leaves="packets"),
                                     MeshOptions(traversal="stack", leaves="scalar"),
                                     MeshOptions(traversal="wide4", leaves="scalar", instancing=False)],
                         ids=["wide8-packets", "stack-scalar", "wide4-flattened"])
def test_single_sided_quads_are_met_from_their_front_only(tmp_path, options, object_mirrored, normals):
    mirror = -1 if object_mirrored else 1
    r = geometry(quads_file(tmp_path, normals), options, (1.0, 1.0, float(mirror)))
    assert r.geometry.has_alpha  # the culling code is compiled in
    assert r.features().has_instances == options.instancing
    out = SurfaceProbe(r.geometry).shoot(*rays())
    for row, (side, quad) in enumerate((side, q) for side in SIDES for q in QUADS):
        name, front = quad[0], quad[6] * mirror
        seen = front == 0 or front == side
        assert out[row, SurfaceProbe.HIT] == int(seen), (name, side)
        if seen:
            assert out[row, SurfaceProbe.T] == pytest.approx(5.0, abs=1e-5), (name, side)
            normal = out[row, SurfaceProbe.N_GEO]
            np.testing.assert_allclose(normal, [0.0, 0.0, front or mirror], atol=1e-6, err_msg=f"{name} from {side}")
            assert out[row, SurfaceProbe.FRONT] == int((front or mirror) == side), (name, side)
            np.testing.assert_allclose(out[row, SurfaceProbe.N_SHADING], normal, atol=1e-6)


def test_the_mirrored_quads_are_placed_as_the_plain_one(tmp_path):
    """What the rays above rely on: every quad covers the square its translation centres (the
    mirrors map the unit quad onto itself)."""
    r = geometry(quads_file(tmp_path), MeshOptions(traversal="stack", leaves="scalar", instancing=False))
    tris = r.geometry.data.tri_vertices.astype(np.float64)
    assert len(tris) == 2 * len(QUADS)
    boxes = sorted((tuple(np.round(t.min(axis=(0, 1)), 6)), tuple(np.round(t.max(axis=(0, 1)), 6)))
                   for t in tris.reshape(len(QUADS), 2, 3, 3))
    expected = sorted((tuple(np.add(q[1], [-0.5, -0.5, 0.0])), tuple(np.add(q[1], [0.5, 0.5, 0.0]))) for q in QUADS)
    np.testing.assert_allclose(np.array(boxes), np.array(expected), atol=1e-6)

"""A glass sphere made of triangles renders like the analytic glass sphere, wound either way.

Every ray that leaves a glass mesh meets a back face, so this is where wrong back-face hits show
(barycentrics, and the point, normal and uv built from them): a finely tessellated icosphere with
smooth vertex normals, as an OBJ, against the analytic sphere (`type = "sphere"`) of the same
radius, both smooth dielectric (roughness 0, ior 1.5), in front of an emissive checker (a wall
behind and a floor, quads of black albedo, so the glass is all a path scatters off before it ends
on an emitter or the sky: refraction errors move checker edges, and no diffuse bounce adds
noise), 'path' integrator. The mesh is also rendered with every face wound the other way (vertex normals
unchanged): the outside of a closed mesh is the one its volume says (renderer/scene/orientation.py
turns such a mesh the right way out when it is loaded), so the image must not change.

Decision rule: tests/stats/image_tests.assert_agree (Mitsuba's per-pixel z-test at ALPHA = 0.01,
Sidak-corrected over the pixels, 99.75 % of the pixel channels must pass; then the image means),
renders on independent seeds.

Why the tessellation is invisible here. The vertices lie on the sphere and the vertex normals are
exactly radial, so the interpolated normal at a hit is the radial direction through the hit point
itself: the only difference from the analytic sphere is that each facet lies inside it, by at
most GAP = 3.6e-5 m for 6 subdivisions of radius R = 0.5 (the first test computes it from the
mesh). Along a ray at incidence i the analytic hit lies at most GAP / cos i further on, where the
radial normal has turned by GAP tan i / R = 7.1e-5 tan i rad; through the two interfaces of the
ball a path's direction changes by at most ~4 times that, 2.9e-4 tan i rad. The rays of one pixel
(0.016 rad at the camera, ~4 cm wide at the ball) leave the ball, a lens of focal length
n R / (2 (n - 1)) = 0.75 m, fanned over ~0.05 rad, so the checker edges in a pixel's view move by
at most 0.6 % tan i of its width. Only pixels with an edge in view change, and those are the
noisiest: split evenly between light and dark (green contrast 0.75) a sample has sd 0.375, the
mean 0.023 at SPP, while the edge moves the mean by at most 0.75 x 0.006 tan i = 0.0043 tan i:
0.19 tan i standard errors, below 0.4 on the 80 % of the ball's disc where tan i < 2, far below
the Sidak critical value (4.4). (5 subdivisions, GAP 4x larger, would give 0.8 tan i.) At 16x
the samples (4,096 spp, where a bias has 4x the z it has here) both windings passed the
per-pixel rule on every channel, their largest |z| (4.1, 3.1) no larger than that between two
renders of the analytic sphere on different seeds (4.1).
"""
from pathlib import Path

import numpy as np
import pytest
import trimesh

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from tests.scene_builder import scene_from_toml
from tests.stats.image_tests import assert_agree

SUBDIVISIONS = 6
RADIUS = 0.5
CENTRE = (0.0, 0.55, 0.0)  # just above the floor: no contact with it
SPP = 256
SEEDS = {"analytic": 11, "mesh": 22, "mesh_flipped": 33}  # independent renders
CHECKER = 0.3  # edge of a checker square, metres

HEADER = """
[scene]
geometry = "mesh"
[camera]
position = [0.0, 0.8, 2.6]
look_at = [0.0, 0.55, 0.0]
fov = 30
[render]
width = 32
height = 32
max_depth = -1
[environment]
type = "sky"
[materials.glass]
type = "dielectric"
base_color = [1.0, 1.0, 1.0]
roughness = 0.0
ior = 1.5
[materials.light]
type = "diffuse"
base_color = [0.0, 0.0, 0.0]
emission = [1.0, 0.9, 0.8]
[materials.dark]
type = "diffuse"
base_color = [0.0, 0.0, 0.0]
emission = [0.1, 0.15, 0.2]
"""


def _vec(v):
    return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"


def checker() -> str:
    """Emissive squares: a wall 1.2 m behind the ball (facing it) and the floor under and around it."""
    quads = []
    for i in range(-5, 5):
        x = (i + 0.5) * CHECKER
        for j in range(6):  # the wall, z = -1.2, from the floor up to 1.8 m
            quads.append(((x, (j + 0.5) * CHECKER, -1.2), (90.0, 0.0, 0.0), (i + j) % 2))
        for j in range(8):  # the floor, y = 0, from the wall to 1.2 m in front of the ball
            quads.append(((x, 0.0, -1.2 + (j + 0.5) * CHECKER), (0.0, 0.0, 0.0), (i + j) % 2))
    return "".join(f'[[objects]]\ntype = "quad"\nmaterial = "{"light" if lit else "dark"}"\n'
                   f"size = [{CHECKER}, {CHECKER}]\nrotate = {_vec(rotate)}\ntranslate = {_vec(centre)}\n"
                   for centre, rotate, lit in quads)


def icosphere():
    return trimesh.creation.icosphere(subdivisions=SUBDIVISIONS, radius=RADIUS)


def write_obj(path: Path, mesh, flip: bool) -> Path:
    """The icosphere with exactly radial vertex normals; flip: every face wound the other way."""
    v = np.asarray(mesh.vertices)
    n = v / np.linalg.norm(v, axis=1, keepdims=True)
    faces = np.asarray(mesh.faces)[:, ::-1] if flip else np.asarray(mesh.faces)
    lines = [f"v {a:.9f} {b:.9f} {c:.9f}" for a, b, c in v]
    lines += [f"vn {a:.9f} {b:.9f} {c:.9f}" for a, b, c in n]
    lines += [f"f {a}//{a} {b}//{b} {c}//{c}" for a, b, c in faces + 1]
    path.write_text("\n".join(lines) + "\n")
    return path


def render(tmp_path: Path, name: str, ball: str):
    scene = scene_from_toml(tmp_path, HEADER + checker() + ball, name)
    r = Renderer(scene)
    r.render(CameraFrame.from_spec(scene.camera), SPP, integrator="path", seed=SEEDS[name])
    assert r.film.stats()["rejected"] == 0, f"{name}: non-finite samples"
    return r.film.mean_image().astype(np.float64), r.film.variance_of_mean_image().astype(np.float64)


@pytest.fixture(scope="module")
def analytic(tmp_path_factory):
    ball = f'[[objects]]\ntype = "sphere"\nmaterial = "glass"\nradius = {RADIUS}\ntranslate = {_vec(CENTRE)}\n'
    return render(tmp_path_factory.mktemp("analytic"), "analytic", ball)


def test_tessellation_stays_within_the_gap_the_docstring_assumes():
    """The facets lie inside the sphere by at most GAP = 3.6e-5 m (the foot of the centre on each
    face's plane is the face's point nearest the centre: the faces are near-equilateral, so the
    foot lies inside them), and the vertices on it."""
    mesh = icosphere()
    v = np.asarray(mesh.vertices)
    assert np.allclose(np.linalg.norm(v, axis=1), RADIUS, rtol=1e-12)
    tris = v[np.asarray(mesh.faces)]
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    foot_distance = np.abs((tris[:, 0] * normal).sum(axis=1))
    foot = foot_distance[:, None] * normal
    for i in range(3):  # the foot is inside each face
        edge, to_foot = tris[:, (i + 1) % 3] - tris[:, i], foot - tris[:, i]
        assert ((np.cross(edge, to_foot) * normal).sum(axis=1) > 0).all()
    gap = RADIUS - foot_distance.min()
    assert gap <= 3.6e-5, f"the tessellation strays {gap:.2e} m from the sphere"


@pytest.mark.parametrize("flip", [False, True], ids=["wound_as_generated", "wound_the_other_way"])
def test_glass_mesh_renders_like_the_analytic_sphere(tmp_path, analytic, flip):
    obj = write_obj(tmp_path / "ball.obj", icosphere(), flip)
    ball = f'[[objects]]\ntype = "mesh"\nfile = "{obj.name}"\nmaterial = "glass"\ntranslate = {_vec(CENTRE)}\n'
    name = "mesh_flipped" if flip else "mesh"
    mesh = render(tmp_path, name, ball)
    assert_agree(analytic, mesh, ("analytic sphere", name))

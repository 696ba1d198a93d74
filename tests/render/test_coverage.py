"""glTF coverage and vertex colours in renders: a MASK cut-out shows what lies behind its holes and
casts a checkered shadow, OPAQUE ignores alpha, a BLEND veil (OBJ dissolve) passes 1 - alpha of
the light behind it, COLOR_0 multiplies the base colour and its alpha the coverage.

Pixels are compared exactly where the answer does not depend on the random samples: those whose
footprint (every jittered camera ray of the pixel) lies inside one region of the pattern."""
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.description import CameraSpec, EnvironmentSpec, MaterialSpec, MeshObject, RenderSettings, Scene
from tests.data import make_test_models as models
from tests.stats.image_tests import ALPHA, mean_z, pixel_z_test

DATA = Path(__file__).resolve().parents[1] / "data"
BLACK = EnvironmentSpec(kind="constant", color=(0.0, 0.0, 0.0))
CELL = 0.5  # the cut-out's checker cells, metres (4 x 4 over its 2 m)


def footprints(width, height, fov, distance):
    """Per pixel (rows from the top), the x and y ranges it covers on the plane `distance` ahead of
    a camera looking down -z (x right, y up), as camera.generate_ray jitters inside the pixel:
    (x0, x1) of shape (W,) and (y0, y1) of shape (H,)."""
    tan = math.tan(math.radians(fov) / 2.0)
    xs = (2.0 * np.arange(width + 1) / width - 1.0) * tan * (width / height) * distance
    ys = (2.0 * np.arange(height + 1) / height - 1.0) * tan * distance
    return xs[:-1], xs[1:], ys[:-1][::-1], ys[1:][::-1]


def cells(x0, x1, y0, y1, margin):
    """The cut-out's texel (row, column) under each pixel, -1 where the footprint (grown by
    `margin`) leaves the quad or straddles two cells: (H, W) arrays."""
    col_a, col_b = np.floor((x0 - margin + 1.0) / CELL), np.floor((x1 + margin + 1.0) / CELL)
    row_a, row_b = np.floor((1.0 - y1 - margin) / CELL), np.floor((1.0 - y0 + margin) / CELL)
    col = np.where((col_a == col_b) & (col_a >= 0) & (col_a < 4), col_a, -1)
    row = np.where((row_a == row_b) & (row_a >= 0) & (row_a < 4), row_a, -1)
    rows, cols = np.meshgrid(row, col, indexing="ij")
    decided = (rows >= 0) & (cols >= 0)
    return np.where(decided, rows, -1).astype(int), np.where(decided, cols, -1).astype(int)


def opaque_cell(rows, cols):
    """Whether the cut-out's texel is opaque (tests/data/make_test_models.CUTOUT)."""
    return models.CUTOUT[rows, cols, 3] == 255


def scene_with(objects, camera, width, height, materials=(), max_depth=8):
    return Scene(name="coverage", path=None, geometry="mesh", camera=camera,
                 render=RenderSettings(width=width, height=height, max_depth=max_depth), environment=BLACK,
                 materials=tuple(materials), mesh_objects=tuple(objects))


def render(scene, spp, integrator, max_depth=None, seed=0):
    r = Renderer(scene)
    r.render(CameraFrame.from_spec(scene.camera), spp, integrator=integrator, max_depth=max_depth, seed=seed)
    return r


def cutout_as(tmp_path, mode):
    """tests/data/cutout.gltf with its material's alphaMode replaced."""
    doc = json.loads((DATA / "cutout.gltf").read_text())
    doc["materials"][0]["alphaMode"] = mode
    shutil.copy(DATA / "cutout.png", tmp_path / "cutout.png")
    path = tmp_path / f"cutout_{mode.lower()}.gltf"
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize("mode", ["MASK", "OPAQUE"])
def test_mask_shows_what_lies_behind_its_holes(tmp_path, mode):
    """The cut-out 4 m in front of the camera, a wall 2 m behind it: the first hit's distance is
    below 4.6 m on the quad and above 6 m on the wall. MASK: the wall shows through exactly the
    transparent cells; OPAQUE: nowhere."""
    width = height = 64
    fov = 40.0
    camera = CameraSpec(position=(0.0, 0.0, 4.0), look_at=(0.0, 0.0, 0.0), fov=fov)
    scene = scene_with([MeshObject(kind="mesh", file=cutout_as(tmp_path, mode)),
                        MeshObject(kind="quad", material="wall", size=(20.0, 20.0), rotate=(90.0, 0.0, 0.0),
                                   translate=(0.0, 0.0, -2.0))],
                       camera, width, height, [MaterialSpec("wall", "diffuse", (0.5, 0.5, 0.5))])
    depth = render(scene, 4, "depth").image()[..., 0]
    rows, cols = cells(*footprints(width, height, fov, 4.0), margin=1e-4)
    decided = rows >= 0
    assert decided.sum() > 0.5 * width * height * (2.0 / (2 * 4 * math.tan(math.radians(fov) / 2))) ** 2
    on_quad = depth[decided] < 4.6
    assert (on_quad | (depth[decided] > 6.0)).all(), "a pixel mixes the quad and the wall"
    expected = opaque_cell(rows[decided], cols[decided]) if mode == "MASK" else np.ones(decided.sum(), bool)
    np.testing.assert_array_equal(on_quad, expected)


SHADOW_SIZE = 64


@pytest.fixture(scope="module")
def shadow_renderer():
    """The scene of test_mask_casts_a_checkered_shadow."""
    camera = CameraSpec(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0), fov=90.0)
    scene = scene_with([MeshObject(kind="quad", material="wall", size=(14.0, 14.0), rotate=(90.0, 0.0, 0.0)),
                        MeshObject(kind="mesh", file=DATA / "cutout.gltf", translate=(0.0, 0.0, 8.0)),
                        MeshObject(kind="sphere", material="lamp", radius=0.02, translate=(0.0, 0.0, 10.0))],
                       camera, SHADOW_SIZE, SHADOW_SIZE, [MaterialSpec("wall", "diffuse", (0.8, 0.8, 0.8)),
                                                          MaterialSpec("lamp", "diffuse", (0.0, 0.0, 0.0),
                                                                       emission=(2000.0, 2000.0, 2000.0))])
    return Renderer(scene)


# (`nee` traces its shadow rays at the same call site as `mis`: renderer/integrators/tracer.py)
@pytest.mark.parametrize("integrator", ["mis"])
def test_mask_casts_a_checkered_shadow(shadow_renderer, integrator):
    """A small lamp 10 m above a white wall, the cut-out at 8 m between them, direct light only
    (max depth 2), black sky. Seen from 5 m by a camera whose field of view (90 degrees) maps the
    wall's points onto the cut-out's through the lamp's centre (a wall point x lies in the shadow
    of the cut-out's point x / 5 = the camera's image-plane coordinate): the wall is exactly black
    behind opaque cells (shadow rays stop there) and lit behind holes (shadow rays pass), except
    within the lamp's penumbra (radius 0.02 m: 0.016 m on the cut-out's scale) of a cell edge."""
    size = SHADOW_SIZE
    r = shadow_renderer
    r.reset()
    r.render(CameraFrame.from_spec(r.scene.camera), 4, integrator=integrator, max_depth=2, seed=0)
    image = r.image()[..., 1]
    rows, cols = cells(*footprints(size, size, 90.0, 1.0), margin=0.02)
    decided = rows >= 0
    assert decided.sum() > 0.6 * size * size
    lit = image[decided] > 0.0
    np.testing.assert_array_equal(lit, ~opaque_cell(rows[decided], cols[decided]))
    assert image[decided][lit].min() > 1e-3 * image[decided][lit].mean()


def test_blend_veil_passes_the_rest_of_the_light(tmp_path):
    """An OBJ quad of dissolve d = 0.3 (alpha BLEND, base alpha 0.3, black) over an emitter of
    radiance 1 that fills the view: camera rays see the emitter with probability 0.7, so the image
    mean is 0.7 (z-test of the image mean at the suite's level, pixels independent)."""
    (tmp_path / "veil.mtl").write_text("newmtl veil\nKd 0 0 0\nd 0.3\n")
    (tmp_path / "veil.obj").write_text("mtllib veil.mtl\nv -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\n"
                                       "usemtl veil\nf 1 2 3 4\n")
    camera = CameraSpec(position=(0.0, 0.0, 4.0), look_at=(0.0, 0.0, 0.0), fov=30.0)
    scene = scene_with([MeshObject(kind="mesh", file=tmp_path / "veil.obj"),
                        MeshObject(kind="quad", material="lamp", size=(40.0, 40.0), rotate=(90.0, 0.0, 0.0),
                                   translate=(0.0, 0.0, -1.0))],
                       camera, 32, 32, [MaterialSpec("lamp", "diffuse", (0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0))])
    r = render(scene, 64, "path", max_depth=1)
    assert r.features().has_alpha
    mean, var = r.image(), r.film.variance_of_mean_image()
    critical = stats.norm.isf(ALPHA / 2)
    for channel in range(3):
        z = mean_z(mean, var, 0.7, channel)
        assert abs(z) < critical, f"channel {channel}: mean {mean[..., channel].mean():.4f}, z = {z:.2f}"


def test_vertex_colors_multiply_base_colour_and_coverage():
    """tests/data/colored_quads.gltf in the albedo view: the first quad's base colour times its
    COLOR_0, linear in position, so that each pixel's expected mean is the colour at its centre
    (per-pixel z-test against that value); the second quad's COLOR_0 alpha runs 0 -> 1 left to
    right under MASK 0.5, so only its right half is there; the third has no COLOR_0 (white)."""
    width, height, fov = 96, 32, 24.8
    camera = CameraSpec(position=(0.0, 0.0, 5.0), look_at=(0.0, 0.0, 0.0), fov=fov)
    scene = scene_with([MeshObject(kind="mesh", file=DATA / "colored_quads.gltf")], camera, width, height)
    r = render(scene, 16, "albedo")
    assert r.features().has_vertex_colors and r.features().has_alpha
    mean, var = r.image(), r.film.variance_of_mean_image()
    x0, x1, y0, y1 = footprints(width, height, fov, 5.0)
    xs, ys = np.meshgrid(0.5 * (x0 + x1), 0.5 * (y0 + y1))
    inside = lambda cx, lo=-1.0, hi=1.0: (((x0 - cx >= lo) & (x1 - cx <= hi))[None, :]
                                          & ((y0 >= -1.0) & (y1 <= 1.0))[:, None])
    tinted = inside(models.COLORED_CENTRES[0])
    base = np.array(models.COLORED_MATERIALS[0]["pbrMetallicRoughness"]["baseColorFactor"][:3])
    expected = base * models.tinted_color(xs - models.COLORED_CENTRES[0], ys)[..., :3]
    passed, fraction, *_ = pixel_z_test(mean[tinted][None], var[tinted][None], expected[tinted][None],
                                        np.zeros_like(expected[tinted][None]))
    assert passed, f"{fraction:.2%} of the tinted quad's pixels agree with its interpolated colour"
    faded = models.COLORED_CENTRES[1]
    gray = models.COLORED_MATERIALS[1]["pbrMetallicRoughness"]["baseColorFactor"][0]
    assert (mean[inside(faded, -1.0, -1e-4)] == 0.0).all(), "alpha < cutoff: the faded quad's left half is a hole"
    assert np.allclose(mean[inside(faded, 1e-4, 1.0)], gray, atol=1e-6)
    plain = np.array(models.COLORED_MATERIALS[2]["pbrMetallicRoughness"]["baseColorFactor"][:3], np.float32)
    # White corners interpolated: (1 - b1 - b2) + b1 + b2 is 1 to within its four f32 roundings
    # (u = 2^-24 each), the tint's product and the film's running mean add a few more: 8 u.
    assert np.allclose(mean[inside(models.COLORED_CENTRES[2])], plain, rtol=8 * 2.0**-24, atol=0), "no COLOR_0: white"

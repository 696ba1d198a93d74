"""The `water` generator (renderer/scene/generators.py, renderer/scene/waves.py) and the pool scene.

The wave formula is written out again here, independently, for the checks: heights and positions
against it, analytic normals against finite differences of the surface, the mesh as a grid, the
one-line errors for bad parameters, and the pool scene rendering finite values.
"""
import math
from pathlib import Path

import numpy as np
import pytest

from renderer.scene import load_scene
from renderer.scene.errors import SceneError
from renderer.scene.generators import generate, triangle_count
from renderer.scene.waves import Wave, from_params, loop_sum, problems
from tests.scene.test_generators import check_mesh, face_normals

REPO = Path(__file__).resolve().parents[2]

WAVES = (  # (direction deg, wavelength, amplitude, phase deg, steepness)
    (20.0, 1.1, 0.05, 0.0, 0.6),
    (-35.0, 0.7, 0.03, 40.0, 0.5),
    (75.0, 0.45, 0.015, 110.0, 0.4),
    (140.0, 0.3, 0.008, 200.0, 0.0),
)


def tables(waves, steep=True):
    keys = ("direction", "wavelength", "amplitude", "phase", "steepness")
    return tuple({k: (v if steep or k != "steepness" else 0.0) for k, v in zip(keys, w)} for w in waves)


def formula(waves, x0, z0):
    """The displaced point of grid point (x0, z0), straight from the definition (float64)."""
    p = np.array([x0, 0.0, z0], np.float64)
    for direction, length, amplitude, phase, q in waves:
        a = math.radians(direction)
        d = np.array([math.cos(a), 0.0, math.sin(a)])
        theta = 2.0 * math.pi / length * (d[0] * x0 + d[2] * z0) + math.radians(phase)
        p += np.array([0.0, amplitude * math.cos(theta), 0.0]) - q * amplitude * math.sin(theta) * d
    return p


def grid_points(resolution, size):
    coords = np.linspace(-0.5 * size, 0.5 * size, resolution + 1)
    return [(x, z) for z in coords for x in coords]  # row by row in z, then x (the generator's order)


@pytest.mark.parametrize("steep", [False, True], ids=["sine", "gerstner"])
def test_positions_match_the_wave_formula(steep):
    resolution, size = 24, 3.0
    positions, indices, normals = generate("water", {"resolution": resolution, "size": size,
                                                     "waves": tables(WAVES, steep)})
    check_mesh(positions, indices, normals)
    waves = [w if steep else w[:4] + (0.0,) for w in WAVES]
    expected = np.array([formula(waves, x, z) for x, z in grid_points(resolution, size)])
    np.testing.assert_allclose(positions, expected, atol=2e-6)  # float32 storage
    assert np.abs(positions[:, 1]).max() <= sum(w[2] for w in WAVES) + 1e-6
    if not steep:  # a height field: x and z stay on the grid
        np.testing.assert_array_equal(positions[:, [0, 2]], np.float32([(x, z) for x, z in grid_points(resolution, size)]))


def test_sine_normals_are_the_height_gradient():
    """Steepness 0: n ~ (-dh/dx, 1, -dh/dz), the gradient by central differences of the formula."""
    resolution, size, h = 24, 2.5, 1e-5
    waves = [w[:4] + (0.0,) for w in WAVES]
    _, _, normals = generate("water", {"resolution": resolution, "size": size, "waves": tables(WAVES, False)})
    for (x, z), n in zip(grid_points(resolution, size), normals):
        dh_dx = (formula(waves, x + h, z)[1] - formula(waves, x - h, z)[1]) / (2 * h)
        dh_dz = (formula(waves, x, z + h)[1] - formula(waves, x, z - h)[1]) / (2 * h)
        expected = np.array([-dh_dx, 1.0, -dh_dz]) / math.sqrt(dh_dx ** 2 + 1.0 + dh_dz ** 2)
        np.testing.assert_allclose(n, expected, atol=2e-6)


def test_gerstner_normals_are_the_surface_cross_product():
    """Steepness > 0: n ~ dP/dz0 x dP/dx0, the tangents by central differences of the formula."""
    resolution, size, h = 24, 2.5, 1e-5
    _, _, normals = generate("water", {"resolution": resolution, "size": size, "waves": tables(WAVES)})
    for (x, z), n in zip(grid_points(resolution, size), normals):
        tx = (formula(WAVES, x + h, z) - formula(WAVES, x - h, z)) / (2 * h)
        tz = (formula(WAVES, x, z + h) - formula(WAVES, x, z - h)) / (2 * h)
        expected = np.cross(tz, tx)
        np.testing.assert_allclose(n, expected / np.linalg.norm(expected), atol=2e-6)


def test_grid_topology_counts_and_folds():
    """A watertight grid: (r + 1)^2 vertices, 2 r^2 triangles, every interior edge shared by two
    triangles and 4 r boundary edges; no fold (every face faces up, as every normal does) and no
    NaN, even with the steepness sum close to 1."""
    resolution = 64
    waves = ({"wavelength": 0.5, "amplitude": 0.075, "steepness": 1.0, "direction": 30.0},
             {"wavelength": 0.35, "amplitude": 0.01, "steepness": 0.3, "direction": -60.0})
    params = {"resolution": resolution, "size": 2.0, "waves": waves}
    assert 0.9 < loop_sum(from_params(params)[0]) < 1.0
    positions, indices, normals = generate("water", params)
    check_mesh(positions, indices, normals)
    assert len(positions) == (resolution + 1) ** 2
    assert len(indices) == 2 * resolution ** 2 == triangle_count("water", params)
    edges = np.sort(np.concatenate([indices[:, [0, 1]], indices[:, [1, 2]], indices[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert set(counts) == {1, 2} and np.count_nonzero(counts == 1) == 4 * resolution
    face, _ = face_normals(positions, indices)
    assert face[:, 1].min() > 0.0 and normals[:, 1].min() > 0.0
    # The interpolated normals follow the faces, except at the sharp crests this near-looping set
    # makes (curvature radius ~ a cell there): on every face they agree to within 50 degrees.
    corner_normals = normals[indices].astype(np.float64).mean(axis=1)
    corner_normals /= np.linalg.norm(corner_normals, axis=1, keepdims=True)
    agreement = np.einsum("ij,ij->i", face, corner_normals)
    assert np.median(agreement) > 0.995 and agreement.min() > 0.64


def test_random_set_is_seeded_and_documented():
    params = {"resolution": 64, "size": 4.0, "wave_count": 6, "wavelength": 0.8, "amplitude": 0.012,
              "direction": 30.0, "spread": 45.0, "steepness": 0.4, "seed": 3}
    a, b = generate("water", params), generate("water", params)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    c = generate("water", {**params, "seed": 4})
    assert not np.array_equal(a[0], c[0])
    waves, _ = from_params(params)
    assert len(waves) == 6
    assert all(0.2 - 1e-12 <= w.wavelength <= 0.8 for w in waves)
    assert all(abs(w.amplitude / w.wavelength - 0.012 / 0.8) < 1e-12 for w in waves)  # equally steep
    assert all(-15.0 <= w.direction <= 75.0 and 0.0 <= w.phase < 360.0 and w.steepness == 0.4 for w in waves)
    assert abs(loop_sum(waves) - 6 * 0.4 * 2 * math.pi * 0.012 / 0.8) < 1e-12
    # The defaults make a valid random set.
    positions, indices, normals = generate("water", {"resolution": 64})
    check_mesh(positions, indices, normals)


def test_bad_parameters_raise_from_the_generator():
    with pytest.raises(ValueError, match="steepness too high"):
        generate("water", {"resolution": 16, "waves": ({"wavelength": 1.0, "amplitude": 0.2, "steepness": 1.0},)})
    with pytest.raises(ValueError, match="shorter than two grid cells"):
        generate("water", {"resolution": 16, "size": 4.0, "waves": ({"wavelength": 0.4, "amplitude": 0.01},)})
    assert problems([Wave(wavelength=-1.0, amplitude=0.1)], 0.01) == "wave 0: wavelength must be positive, got -1"


# --- scene files ------------------------------------------------------------------------------------

HEADER = """[scene]
geometry = "mesh"

[materials.water]
type = "dielectric"
ior = 1.33

[[objects]]
type = "generated"
generator = "water"
material = "water"
"""


def load_error(tmp_path, body: str) -> str:
    path = tmp_path / "water.toml"
    path.write_text(HEADER + body, encoding="utf-8")
    with pytest.raises(SceneError) as info:
        load_scene(path)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{path}: ")
    return message[len(f"{path}: "):]


BAD = {
    "loops": ('waves = [{ wavelength = 1.0, amplitude = 0.1, steepness = 0.9 },'
              ' { wavelength = 0.5, amplitude = 0.05, steepness = 0.8 }]\n',
              "objects[0]: steepness too high: the sum over the waves of steepness * 2 pi * amplitude / wavelength "
              "is 1.07, it must stay below 1"),
    "random set loops": ("wave_count = 8\nsteepness = 1.0\namplitude = 0.05\n", "objects[0]: steepness too high"),
    "zero wavelength": ('waves = [{ wavelength = 1.0, amplitude = 0.01 }, { wavelength = 0, amplitude = 0.01 }]\n',
                        "objects[0].waves[1].wavelength: 0 is out of range (allowed: > 0)"),
    "negative amplitude": ('waves = [{ wavelength = 1.0, amplitude = -0.01 }]\n',
                           "objects[0].waves[0].amplitude: -0.01 is out of range (allowed: >= 0)"),
    "steepness above 1": ('waves = [{ wavelength = 1.0, amplitude = 0.01, steepness = 1.5 }]\n',
                          "objects[0].waves[0].steepness: 1.5 is out of range (allowed: [0, 1])"),
    "missing amplitude": ('waves = [{ wavelength = 1.0 }]\n', "objects[0].waves[0]: missing required field 'amplitude'"),
    "unknown wave field": ('waves = [{ wavelength = 1.0, amplitude = 0.01, height = 2 }]\n',
                           "objects[0].waves[0]: unknown field 'height' (allowed: direction, wavelength, amplitude, "
                           "phase, steepness)"),
    "waves not tables": ("waves = 3\n", "objects[0].waves: expected an array of tables, got integer 3"),
    "wave not a table": ("waves = [1.0]\n", "objects[0].waves[0]: expected a table, got float 1.0"),
    "too short for the grid": ('resolution = 64\nsize = 8\nwaves = [{ wavelength = 0.2, amplitude = 0.001 }]\n',
                               "objects[0]: waves[0]: wavelength 0.2 m is shorter than two grid cells (0.25 m"),
    "random set too short": ("resolution = 16\nsize = 4\nwavelength = 1.0\n",
                             "objects[0]: wavelength: random wave"),
    "resolution too large": ("resolution = 5000\n", "objects[0].resolution: 5000 is out of range (allowed: [2, 2048])"),
    "resolution 1": ("resolution = 1\n", "objects[0].resolution: 1 is out of range (allowed: [2, 2048])"),
    "waves and seed": ('seed = 4\nwaves = [{ wavelength = 1.0, amplitude = 0.01 }]\n',
                       "objects[0]: seed describes a random wave set and cannot be combined with `waves`"),
    "waves and two random fields": ('wave_count = 2\nspread = 10\nwaves = [{ wavelength = 1.0, amplitude = 0.01 }]\n',
                                    "objects[0]: wave_count, spread describe a random wave set"),
    "terrain field on water": ("height = 1\n", "objects[0].height: only allowed with generator 'terrain' or 'light_panels'"),
}


@pytest.mark.parametrize("body, expected", BAD.values(), ids=BAD.keys())
def test_bad_scene_parameters_give_one_line_errors(tmp_path, body, expected):
    assert expected in load_error(tmp_path, body)


def test_good_water_object_loads_with_hashable_params(tmp_path):
    path = tmp_path / "water.toml"
    path.write_text(HEADER + 'resolution = 32\nwaves = [{ direction = 10, wavelength = 1.0, amplitude = 0.01 }]\n')
    scene = load_scene(path)
    obj = scene.mesh_objects[0]
    hash(obj)  # the model stays hashable with an array of tables among the parameters
    params = dict(obj.params)
    assert params["waves"] == ((("amplitude", 0.01), ("direction", 10.0), ("phase", 0.0), ("steepness", 0.0),
                                ("wavelength", 1.0)),)
    positions, _, _ = generate("water", params)
    assert len(positions) == 33 ** 2


# --- the pool ---------------------------------------------------------------------------------------

def test_pool_scene_loads_and_renders_finite():
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from renderer.scene.catalog import PREFERRED_ORDER, resolve_scene

    assert "pool" in PREFERRED_ORDER
    scene = load_scene(resolve_scene("pool"))
    water = [o for o in scene.mesh_objects if o.generator == "water"]
    assert len(water) == 1
    material = next(m for m in scene.materials if m.name == water[0].material)
    assert material.kind == "dielectric" and material.ior == 1.33
    assert any(max(m.emission) > 0 for m in scene.materials)
    r = Renderer(scene, (32, 32))
    r.render(CameraFrame.from_spec(scene.camera), 4, integrator="mis")
    image = r.image()
    assert image.shape[:2] == (32, 32)
    assert np.isfinite(image).all() and image.min() >= 0.0 and image.mean() > 0.05

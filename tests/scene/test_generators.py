"""Tests for the procedural meshes of `generated` objects, and for the scripts that generate
shipped assets (the "weekend" scene and the textured glTF model)."""
from __future__ import annotations

import importlib.util
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from renderer.scene import load_scene, schema
from renderer.scene.generators import generate, grid_indices, triangle_count, value_noise
from renderer.scene.model_formats import load_mesh_asset
from renderer.scene.srgb import srgb_to_linear
from renderer.scene.mesh_model import uv_transform_matrix

REPO = Path(__file__).resolve().parents[2]


def load_script(name: str):
    spec = importlib.util.spec_from_file_location(name, REPO / "scripts" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def face_normals(positions: np.ndarray, indices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(unit face normals, twice the areas), in float64."""
    p = positions.astype(np.float64)
    cross = np.cross(p[indices[:, 1]] - p[indices[:, 0]], p[indices[:, 2]] - p[indices[:, 0]])
    twice_area = np.linalg.norm(cross, axis=1)
    return cross / twice_area[:, None], twice_area


def check_mesh(positions, indices, normals):
    """The contract of `generate`: dtypes, shapes, valid indices, unit normals, no degenerate
    triangles, every vertex used."""
    assert positions.dtype == np.float32 and normals.dtype == np.float32 and indices.dtype == np.int32
    assert positions.ndim == 2 and positions.shape[1] == 3 and normals.shape == positions.shape
    assert indices.ndim == 2 and indices.shape[1] == 3
    assert all(a.flags.c_contiguous for a in (positions, indices, normals))
    assert np.all(np.isfinite(positions)) and np.all(np.isfinite(normals))
    assert indices.min() == 0 and indices.max() == len(positions) - 1
    assert len(np.unique(indices)) == len(positions)  # no unused vertex
    assert np.all(indices[:, 0] != indices[:, 1]) and np.all(indices[:, 1] != indices[:, 2])
    assert np.all(indices[:, 0] != indices[:, 2])
    np.testing.assert_allclose(np.linalg.norm(normals.astype(np.float64), axis=1), 1.0, atol=1e-6)
    _, twice_area = face_normals(positions, indices)
    edges = np.linalg.norm(np.diff(positions[indices][:, [0, 1, 2, 0]].astype(np.float64), axis=1), axis=2)
    # The loader's degeneracy test (relative to the longest edge), with a wide margin.
    assert np.all(twice_area > 1e-6 * edges.max(axis=1) ** 2)


# --- terrain ---------------------------------------------------------------------------------


@pytest.mark.parametrize("resolution", [2, 3, 17, 64])
def test_terrain_counts_and_extent(resolution):
    size, height = 6.0, 0.75
    positions, indices, normals = generate("terrain", {"resolution": resolution, "size": size,
                                                       "height": height, "seed": 3})
    check_mesh(positions, indices, normals)
    assert len(positions) == (resolution + 1) ** 2
    assert len(indices) == 2 * resolution ** 2 == triangle_count("terrain", {"resolution": resolution})
    assert positions[:, 0].min() == -size / 2 and positions[:, 0].max() == size / 2
    assert positions[:, 2].min() == -size / 2 and positions[:, 2].max() == size / 2
    assert np.all(np.abs(positions[:, 1]) <= height)
    # A regular grid in x and z.
    xs = np.unique(positions[:, 0])
    np.testing.assert_allclose(np.diff(xs), size / resolution, rtol=1e-5)


def test_terrain_faces_up_and_normals_agree_with_faces():
    # 512 cells: the finest noise octave (128 lattice cells) spans 4 grid cells.
    positions, indices, normals = generate("terrain", {"resolution": 512, "size": 10.0, "height": 0.5})
    face, _ = face_normals(positions, indices)
    assert np.all(face[:, 1] > 0)  # counter-clockwise seen from +y: the front side is up
    assert np.all(normals[:, 1] > 0)
    # Finite-difference vertex normals close to the normals of the faces around each vertex.
    per_corner = np.einsum("tij,tj->ti", normals[indices].astype(np.float64), face)
    assert per_corner.min() > 0.95
    assert np.median(per_corner) > 0.998


def test_flat_terrain():
    positions, indices, normals = generate("terrain", {"resolution": 8, "height": 0.0})
    assert np.all(positions[:, 1] == 0.0)
    np.testing.assert_array_equal(normals, np.tile(np.float32([0, 1, 0]), (len(normals), 1)))
    check_mesh(positions, indices, normals)


def test_terrain_is_deterministic_by_seed():
    params = {"resolution": 50, "size": 10.0, "height": 2.0, "seed": 5}
    first = generate("terrain", params)
    again = generate("terrain", dict(params))
    for a, b in zip(first, again):
        np.testing.assert_array_equal(a, b)
    other = generate("terrain", {**params, "seed": 6})
    np.testing.assert_array_equal(first[0][:, [0, 2]], other[0][:, [0, 2]])
    assert np.abs(first[0][:, 1] - other[0][:, 1]).max() > 0.1
    np.testing.assert_array_equal(first[1], other[1])  # the same connectivity


def test_terrain_has_relief():
    """Fractal noise, not a constant: heights use a fair part of the range and vary at several
    scales (a fine grid is rougher at the fine scale than a smooth single octave would be)."""
    h = value_noise(257, seed=1)
    assert h.min() >= -1.0 and h.max() <= 1.0
    assert h.max() - h.min() > 0.5
    steps = np.abs(np.diff(h, axis=1))
    assert steps.max() < 0.2  # continuous


def test_grid_indices_small_case():
    np.testing.assert_array_equal(grid_indices(1), [[0, 2, 1], [1, 2, 3]])


def test_generate_accepts_scene_params_and_fills_defaults(tmp_path):
    text = ('[scene]\ngeometry = "mesh"\n[materials.m]\n[[objects]]\ntype = "generated"\n'
            'generator = "terrain"\nmaterial = "m"\nresolution = 12\nseed = 4\n')
    path = tmp_path / "t.toml"
    path.write_text(text)
    obj = load_scene(path).mesh_objects[0]
    from_scene = generate(obj.generator, obj.params)  # the (name, value) pairs of MeshObject
    direct = generate("terrain", {"resolution": 12, "seed": 4, "size": 10.0, "height": 1.0})
    for a, b in zip(from_scene, direct):
        np.testing.assert_array_equal(a, b)
    defaults = {f.name: f.default for f in schema.GENERATORS_BY_NAME["terrain"].params}
    assert triangle_count("terrain") == 2 * defaults["resolution"] ** 2


def test_unknown_generator_or_parameter():
    with pytest.raises(ValueError, match="unknown generator 'noise'"):
        generate("noise", {})
    with pytest.raises(ValueError, match="no parameter octaves"):
        generate("terrain", {"octaves": 3})


def python_calls(function, *args):
    """(function's result, the Python and builtin function calls it made): a count of work that,
    unlike a stopwatch, does not depend on the machine or on what else runs on it."""
    calls = 0

    def count(frame, event, arg):
        nonlocal calls
        if event in ("call", "c_call"):
            calls += 1

    previous = sys.getprofile()
    sys.setprofile(count)
    try:
        result = function(*args)
    finally:
        sys.setprofile(previous)
    return result, calls


def test_million_triangle_terrain_is_fast():
    """The default terrain (the stress scene's) is >= 1M triangles, made by whole-array numpy
    operations: the Python calls it makes do not grow with its size (at 708 x 708 vertices, a loop
    over rows would add hundreds, one over vertices hundreds of thousands). It takes ~0.2 s here;
    the time bound below only catches a hang, far above what a busy machine can stretch that to."""
    params = {"resolution": 708, "size": 40.0, "height": 3.0, "seed": 7}
    generate("terrain", dict(params, resolution=64))  # (imports numpy's lazily loaded parts first)
    _, small_calls = python_calls(generate, "terrain", dict(params, resolution=64))
    start = time.perf_counter()
    (positions, indices, normals), calls = python_calls(generate, "terrain", params)
    elapsed = time.perf_counter() - start
    assert len(indices) == 1_002_528
    assert calls <= small_calls + 100, (calls, small_calls)
    assert elapsed < 60.0, f"{elapsed:.2f} s"
    assert np.all(np.isfinite(positions)) and np.all(normals[:, 1] > 0)


# --- icosphere -------------------------------------------------------------------------------


@pytest.mark.parametrize("subdivisions, radius", [(0, 1.0), (1, 0.25), (3, 2.0), (4, 1.0)])
def test_icosphere(subdivisions, radius):
    positions, indices, normals = generate("icosphere", {"subdivisions": subdivisions, "radius": radius})
    check_mesh(positions, indices, normals)
    assert len(indices) == 20 * 4 ** subdivisions == triangle_count("icosphere", {"subdivisions": subdivisions})
    assert len(positions) == 10 * 4 ** subdivisions + 2
    np.testing.assert_allclose(np.linalg.norm(positions, axis=1), radius, rtol=1e-6)
    np.testing.assert_allclose(normals, positions / radius, atol=1e-6)
    face, _ = face_normals(positions, indices)
    centroids = positions[indices].astype(np.float64).mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", face, centroids) > 0)  # counter-clockwise from outside


def test_icosphere_defaults_and_determinism():
    a = generate("icosphere")
    b = generate("icosphere", {"subdivisions": 3, "radius": 1.0})
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


# --- light_panels ----------------------------------------------------------------------------


def test_light_panels_geometry():
    """Square panels of panel_size in the plane y = height, facing down, one per cell, jittered by
    at most a quarter of the gap between panel and cell, so they never overlap."""
    params = {"count_x": 7, "count_z": 5, "size": 2.0, "panel_size": 0.05, "height": 1.5, "seed": 3}
    positions, indices, normals = generate("light_panels", params)
    check_mesh(positions, indices, normals)
    panels = 7 * 5
    assert len(indices) == 2 * panels == triangle_count("light_panels", params)
    assert len(positions) == 4 * panels
    assert np.all(positions[:, 1] == np.float32(1.5))
    np.testing.assert_array_equal(normals, np.tile(np.float32([0, -1, 0]), (len(normals), 1)))
    face, twice_area = face_normals(positions, indices)
    np.testing.assert_allclose(face, np.tile([0.0, -1.0, 0.0], (len(face), 1)), atol=1e-12)
    np.testing.assert_allclose(twice_area, 0.05 ** 2, rtol=1e-4)  # two triangles per square
    corners = positions.astype(np.float64).reshape(panels, 4, 3)
    np.testing.assert_allclose(np.ptp(corners[:, :, 0], axis=1), 0.05, rtol=1e-4)
    np.testing.assert_allclose(np.ptp(corners[:, :, 2], axis=1), 0.05, rtol=1e-4)
    # panel k = j * count_x + i sits near the centre of cell (i, j)
    centre = corners.mean(axis=1)
    i, j = np.arange(panels) % 7, np.arange(panels) // 7
    cell_x, cell_z = -1.0 + (i + 0.5) * (2.0 / 7), -1.0 + (j + 0.5) * (2.0 / 5)
    off_x, off_z = centre[:, 0] - cell_x, centre[:, 2] - cell_z
    assert np.all(np.abs(off_x) <= 0.25 * (2.0 / 7 - 0.05) + 1e-6)
    assert np.all(np.abs(off_z) <= 0.25 * (2.0 / 5 - 0.05) + 1e-6)
    assert np.abs(off_x).max() > 0.01 and np.abs(off_z).max() > 0.01  # jittered
    # deterministic by seed; another seed moves the panels, not the layout
    again = generate("light_panels", dict(params))
    for a, b in zip((positions, indices, normals), again):
        np.testing.assert_array_equal(a, b)
    other = generate("light_panels", {**params, "seed": 4})
    np.testing.assert_array_equal(other[1], indices)
    assert np.abs(other[0] - positions).max() > 0.01


def test_light_panels_defaults():
    positions, indices, normals = generate("light_panels")
    assert len(indices) == 20_000 == triangle_count("light_panels")
    assert np.abs(positions[:, [0, 2]]).max() <= 10.0
    assert np.all(positions[:, 1] == 3.0)
    defaults = {f.name: f.default for f in schema.GENERATORS_BY_NAME["light_panels"].params}
    assert defaults == {"count_x": 100, "count_z": 100, "size": 20.0, "panel_size": 0.05,
                        "height": 3.0, "seed": 0}


def test_generators_sharing_parameter_names_keep_their_own(tmp_path):
    """terrain and light_panels both have size, height and seed, with other defaults and ranges:
    each object gets its own generator's."""
    def load(body):
        path = tmp_path / "g.toml"
        path.write_text('[scene]\ngeometry = "mesh"\n[materials.m]\n[[objects]]\n'
                        'type = "generated"\nmaterial = "m"\n' + body)
        return dict(load_scene(path).mesh_objects[0].params)

    assert load('generator = "terrain"\nresolution = 4\n') == {
        "resolution": 4, "size": 10.0, "height": 1.0, "seed": 0}
    assert load('generator = "light_panels"\nsize = 5\nheight = -1\n') == {
        "count_x": 100, "count_z": 100, "size": 5.0, "panel_size": 0.05, "height": -1.0, "seed": 0}
    from renderer.scene.errors import SceneError
    with pytest.raises(SceneError, match="height: -1 is out of range"):
        load('generator = "terrain"\nheight = -1\n')  # terrain heights are >= 0
    with pytest.raises(SceneError, match="count_x: only allowed with generator 'light_panels', not 'terrain'"):
        load('generator = "terrain"\ncount_x = 3\n')


def test_many_lights_scene():
    """20,000 emitting triangles above a lit floor, a bunny and spheres, under a near-black sky,
    seen from below the panels."""
    scene = load_scene(REPO / "assets" / "scenes" / "many_lights.toml")
    assert scene.geometry == "mesh"
    materials = {m.name: m for m in scene.materials}
    (panels,) = [o for o in scene.mesh_objects if o.kind == "generated"]
    assert panels.generator == "light_panels"
    assert triangle_count(panels.generator, panels.params) == 20_000
    light = materials[panels.material]
    assert light.is_emissive and light.base_color == (0.0, 0.0, 0.0)
    assert [o for o in scene.mesh_objects if o.kind != "generated" and materials[o.material].is_emissive] == []
    kinds = [o.kind for o in scene.mesh_objects]
    assert kinds.count("quad") == 1 and kinds.count("mesh") == 1 and kinds.count("sphere") >= 3
    assert scene.environment.kind == "constant" and max(scene.environment.color) <= 0.02
    positions, _, _ = generate(panels.generator, panels.params)
    world_y = positions[:, 1] * panels.scale[1] + panels.translate[1]
    assert np.all(world_y == 3.0)
    assert scene.camera.position[1] < 3.0
    # the floor is lit to a mid grey: radiance ~ albedo * L * coverage * 0.9 (see the scene file)
    params = dict(panels.params)
    coverage = (params["panel_size"] * params["count_x"] / params["size"]) ** 2
    floor = materials[next(o for o in scene.mesh_objects if o.kind == "quad").material]
    radiance = floor.base_color[0] * max(light.emission) * coverage * 0.9
    assert 0.2 < radiance < 1.0


# --- the stress scene ------------------------------------------------------------------------


def test_stress_scene_has_a_million_triangles():
    scene = load_scene(REPO / "assets" / "scenes" / "stress.toml")
    assert scene.geometry == "mesh"
    generated = [o for o in scene.mesh_objects if o.kind == "generated"]
    assert sum(triangle_count(o.generator, o.params) for o in generated) >= 1_000_000
    assert sum(o.kind == "sphere" for o in scene.mesh_objects) >= 2
    assert scene.environment.kind == "map"
    # The spheres rest on the terrain: sunk into it by a few centimetres, not floating.
    (terrain,) = generated
    assert terrain.rotate == (0.0, 0.0, 0.0)
    positions, _, _ = generate(terrain.generator, terrain.params)
    world = positions.astype(np.float64) * terrain.scale + terrain.translate
    for sphere in (o for o in scene.mesh_objects if o.kind == "sphere"):
        r = sphere.radius * sphere.scale[0]
        depth = r - np.linalg.norm(world - sphere.translate, axis=1).min()  # > 0: touches the ground
        assert 0.0 < depth < 0.1
    # The camera is above the terrain.
    cam = np.array(scene.camera.position)
    near = world[np.hypot(world[:, 0] - cam[0], world[:, 2] - cam[2]) < 1.0]
    assert cam[1] > near[:, 1].max() + 0.5


# --- scripts/make_weekend_scene.py -----------------------------------------------------------


def test_weekend_scene_file_is_the_script_output():
    weekend = load_script("make_weekend_scene")
    shipped = (REPO / "assets" / "scenes" / "weekend.toml").read_text(encoding="utf-8")
    assert shipped == weekend.scene_text(), "regenerate with scripts/make_weekend_scene.py"
    assert weekend.scene_text(weekend.SEED) == weekend.scene_text(weekend.SEED)  # deterministic
    assert weekend.scene_text(1) != weekend.scene_text(2)


def test_weekend_scene_follows_the_book():
    weekend = load_script("make_weekend_scene")
    scene = load_scene(REPO / "assets" / "scenes" / "weekend.toml")
    assert scene.geometry == "mesh"
    cam = scene.camera
    assert (cam.position, cam.look_at, cam.up, cam.fov) == ((13.0, 2.0, 3.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 20.0)
    assert cam.aperture == 0.05 and cam.focus_distance == 10.0  # lens radius = book aperture / 2
    assert scene.environment.kind == "sky"
    assert scene.environment.zenith == (0.5, 0.7, 1.0)
    assert all(o.kind == "sphere" for o in scene.mesh_objects)
    materials = {m.name: m for m in scene.materials}
    ground, *big = scene.mesh_objects[:4]
    assert (ground.radius, ground.translate, materials[ground.material].base_color) == (
        1000.0, (0.0, -1000.0, 0.0), (0.5, 0.5, 0.5))
    expected_big = [((0.0, 1.0, 0.0), "dielectric", (1.0, 1.0, 1.0)),
                    ((-4.0, 1.0, 0.0), "diffuse", (0.4, 0.2, 0.1)),
                    ((4.0, 1.0, 0.0), "conductor", (0.7, 0.6, 0.5))]
    for obj, (centre, kind, colour) in zip(big, expected_big):
        m = materials[obj.material]
        assert (obj.radius, obj.translate, m.kind, m.base_color) == (1.0, centre, kind, colour)
    assert materials[big[0].material].ior == 1.5 and materials[big[2].material].roughness == 0.0

    small = scene.mesh_objects[4:]
    drawn = weekend.spheres()
    assert len(small) == len(drawn) > 400
    for obj, s in zip(small, drawn):
        x, y, z = obj.translate
        assert obj.radius == 0.2 and y == 0.2
        assert s["a"] <= x <= s["a"] + 0.9 and s["b"] <= z <= s["b"] + 0.9
        assert math.dist((x, y, z), (4.0, 0.2, 0.0)) > 0.9
        m = materials[obj.material]
        if s["kind"] == "diffuse":
            assert m.kind == "diffuse" and all(0.0 <= c < 1.0 for c in m.base_color)
        elif s["kind"] == "metal":
            assert m.kind == "conductor" and all(0.5 <= c <= 1.0 for c in m.base_color)
            assert m.roughness == pytest.approx(weekend.fuzz_to_roughness(s["fuzz"]), abs=1e-6)
            assert 0.0 <= m.roughness <= math.sqrt(weekend.FUZZ_TO_ALPHA * 0.5) + 1e-6
        else:
            assert m.kind == "dielectric" and m.ior == 1.5
    kinds = [s["kind"] for s in drawn]
    # 80 / 15 / 5 % in expectation; generous bounds for ~480 draws.
    assert 0.72 < kinds.count("diffuse") / len(kinds) < 0.88
    assert 0.09 < kinds.count("metal") / len(kinds) < 0.21
    assert 0.01 < kinds.count("glass") / len(kinds) < 0.10


# --- scripts/make_textured_gltf.py and assets/models/textured_sphere.glb ---------------------


@pytest.fixture(scope="module")
def textured():
    script = load_script("make_textured_gltf")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the model loads without repairs
        asset = load_mesh_asset(REPO / "assets" / "models" / "textured_sphere.glb")
    return script, asset


def test_textured_glb_is_small_and_reproducible(textured, tmp_path):
    script, _ = textured
    shipped = REPO / "assets" / "models" / "textured_sphere.glb"
    assert shipped.stat().st_size < 300_000
    out = tmp_path / "again.glb"
    assert script.main(["make_textured_gltf.py", str(out)]) == 0
    again = load_mesh_asset(out)
    original = load_mesh_asset(shipped)
    assert again.materials == original.materials
    for a, b in zip(again.images, original.images):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(again.meshes, original.meshes):
        np.testing.assert_array_equal(a.positions, b.positions)
        np.testing.assert_array_equal(a.indices, b.indices)


def test_textured_glb_geometry_matches_the_script(textured):
    script, asset = textured
    assert len(asset.meshes) == 2
    sphere_mesh, floor_mesh = sorted(asset.meshes, key=lambda m: -m.vertex_count)
    for loaded, written, offset in ((sphere_mesh, script.sphere_mesh(), script.SPHERE_CENTER),
                                    (floor_mesh, script.floor_mesh(), (0.0, 0.0, 0.0))):
        np.testing.assert_allclose(loaded.positions, written["positions"] + np.float32(offset), atol=1e-6)
        np.testing.assert_array_equal(loaded.indices, written["indices"].astype(np.int32))
        np.testing.assert_allclose(loaded.normals, written["normals"], atol=1e-6)
        np.testing.assert_array_equal(loaded.uv0, written["uvs"])
        np.testing.assert_allclose(loaded.tangents, written["tangents"], atol=1e-6)
    assert sphere_mesh.triangle_count == 2 * script.SEGMENTS * (script.RINGS - 1)
    np.testing.assert_allclose(asset.bounds, [[-4, 0, -4], [4, 2, 4]], atol=1e-6)


def test_textured_glb_materials_match_the_script(textured):
    script, asset = textured
    by_name = {m.name: m for m in asset.materials}
    assert set(by_name) == {"tiles", "floor"}
    tiles, floor = by_name["tiles"], by_name["floor"]
    assert (tiles.metallic_factor, tiles.roughness_factor, tiles.normal_scale) == (1.0, 1.0, script.SPHERE_NORMAL_SCALE)
    assert (floor.metallic_factor, floor.roughness_factor) == (0.0, 1.0)
    assert floor.normal_scale == pytest.approx(script.FLOOR_NORMAL_SCALE)
    assert tiles.base_color_factor == floor.base_color_factor == (1.0, 1.0, 1.0, 1.0)
    for material in (tiles, floor):
        assert set(material.texture_slots) == {"base_color", "metallic_roughness", "normal"}

    # Samplers: the sphere wraps around (REPEAT) but not over the poles (CLAMP); the floor repeats.
    for ref in tiles.texture_slots.values():
        assert (ref.wrap_s, ref.wrap_t) == ("repeat", "clamp") and not ref.has_transform
    tiling = uv_transform_matrix(scale=script.FLOOR_UV_SCALE)
    for ref in floor.texture_slots.values():
        assert (ref.wrap_s, ref.wrap_t) == ("repeat", "repeat")
        np.testing.assert_allclose(ref.matrix, tiling)
    assert (floor.base_color_texture.mag_filter, floor.base_color_texture.min_filter) == (
        "linear", "linear_mipmap_linear")

    # Images: colour slots sRGB-decoded, data slots as written (k / 255).
    def expected(pixels, srgb):
        rgb = pixels.astype(np.float64) / 255.0
        return srgb_to_linear(rgb) if srgb else rgb

    slots = [(tiles.base_color_texture, script.sphere_base_color(), True),
             (tiles.metallic_roughness_texture, script.sphere_metallic_roughness(), False),
             (tiles.normal_texture, script.tile_normal_map(), False),
             (floor.base_color_texture, script.floor_base_color(), True),
             (floor.metallic_roughness_texture, script.floor_metallic_roughness(), False),
             (floor.normal_texture, script.tile_normal_map(), False)]
    for ref, pixels, srgb in slots:
        image = asset.images[ref.texture].linear()
        assert image.shape == (script.TEX, script.TEX, 4)
        np.testing.assert_allclose(image[..., :3], expected(pixels, srgb), atol=1e-6)
        assert np.all(image[..., 3] == 1.0)
    assert tiles.normal_texture.texture == floor.normal_texture.texture  # one image, shared


def test_textured_glb_textures_say_what_the_docs_say(textured):
    script, _ = textured
    mr = script.sphere_metallic_roughness()
    roughness = mr[..., 1] / 255.0
    assert roughness[0].max() < 0.1 and roughness[-1].min() > 0.9  # smooth top, rough bottom
    assert set(np.unique(mr[..., 2])) == {0, 255}  # metallic stripes
    normal = script.tile_normal_map().astype(np.float64) / 255.0 * 2.0 - 1.0
    np.testing.assert_allclose(np.linalg.norm(normal, axis=-1), 1.0, atol=0.01)
    assert normal[..., 2].min() > 0.3 and (normal[..., 2] < 0.99).mean() > 0.1  # bumps, no flips
    cell = script.TEX // script.TILES
    # Left edge of a tile: the surface rises to the right, so the normal leans left (-x).
    assert normal[cell // 2, cell * 2 + 2, 0] < -0.1
    # Top edge of a tile: the surface rises downwards in the image, so the normal leans up (+y).
    assert normal[cell * 2 + 2, cell // 2, 1] > 0.1
    assert textured_scene_uses_the_file(script)


def textured_scene_uses_the_file(script) -> bool:
    scene = load_scene(REPO / "assets" / "scenes" / "textured.toml")
    (obj,) = scene.mesh_objects
    return obj.kind == "mesh" and obj.file == script.OUT.resolve() and obj.material is None

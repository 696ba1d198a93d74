"""A Mitsuba 3 scene file renders: the Cornell box written as Mitsuba XML (tests/data/mitsuba) and
the catalog's TOML Cornell box give statistically equal images (the suite's per-pixel z-test and
image-mean test at the 1% level, independent seeds), and a Mitsuba scene with a homogeneous medium
inside a null-bounded sphere renders with the medium's light loss."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from scipy import stats

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any, resolve_scene
from tests.stats.image_tests import assert_agree

DATA = Path(__file__).resolve().parents[1] / "data" / "mitsuba"
SIZE = (32, 32)
SPP = 64


def film(scene, seed, size=SIZE):
    renderer = Renderer(scene, size)
    renderer.render(CameraFrame.from_spec(scene.camera), SPP, "mis", max_depth=scene.render.max_depth, seed=seed)
    return renderer.film.mean_image(), renderer.film.variance_of_mean_image()


def test_the_xml_cornell_box_renders_as_the_toml_one():
    xml = load_any(DATA / "cornell_box.xml")
    toml = load_any(resolve_scene("cornell_box"))
    assert xml.render.pixel_filter == "gaussian"  # Mitsuba's default film filter
    toml = dataclasses.replace(toml, render=dataclasses.replace(toml.render, pixel_filter="gaussian"))
    a, b = film(xml, seed=1), film(toml, seed=2)
    assert a[0].mean() > 0.05  # lit
    assert_agree(a, b, ("Mitsuba XML", "TOML"))


def test_a_medium_inside_a_sphere_absorbs(tmp_path):
    def scene(albedo):
        path = tmp_path / f"fog_{albedo}.xml"
        path.write_text(f'''<scene version="3.0.0">
            <sensor type="perspective"><float name="fov" value="30"/>
                <transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
                <film type="hdrfilm"><rfilter type="box"/><integer name="width" value="16"/>
                <integer name="height" value="16"/></film></sensor>
            <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
            <medium type="homogeneous" id="m"><rgb name="sigma_t" value="2"/><rgb name="albedo" value="{albedo}"/></medium>
            <shape type="sphere"><bsdf type="null"/><ref name="interior" id="m"/></shape>
        </scene>''')
        return load_any(path)
    mean, var = film(scene(0.0), seed=3, size=(16, 16))
    block = (slice(6, 10), slice(6, 10))
    # Straight through the sphere, nothing scattered in: each ray keeps exp(-sigma_t chord). The
    # expectation over the 4x4 central pixels, integrated over their area here with numpy.
    u = (np.arange(6 * 64, 10 * 64) + 0.5) / (16 * 64) * 2 - 1
    x, y = np.meshgrid(u * np.tan(np.radians(15)), u * np.tan(np.radians(15)))
    d = np.stack([x, y, -np.ones_like(x)], -1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    miss = np.linalg.norm(np.cross((0.0, 0.0, 4.0), d), axis=-1)  # the ray's distance from the centre
    expected = np.exp(-2.0 * 2.0 * np.sqrt(np.clip(1 - miss**2, 0, None))).mean()
    measured = mean[block][..., 1].mean()
    z = (measured - expected) / np.sqrt(var[block][..., 1].sum()) * 16
    assert abs(z) < stats.norm.isf(0.005), (measured, expected, z)  # two-sided, 1% level
    assert mean[0, 0].mean() == 1.0  # the corner sees the environment only


def _scene_file(tmp_path, name, body, size=32, integrator='<integrator type="direct"/>'):
    path = tmp_path / name
    path.write_text(f'''<scene version="3.0.0">{integrator}
        <sensor type="perspective"><float name="fov" value="40"/>
            <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
            <film type="hdrfilm"><rfilter type="box"/><integer name="width" value="{size}"/>
            <integer name="height" value="{size}"/></film></sensor>
        <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
        {body}</scene>''')
    return load_any(path)


def test_a_checkerboard_on_a_rectangle_is_mitsubas(tmp_path):
    """A wall under a uniform sky, direct light only: each pixel is the checkerboard's reflectance
    where the pixel sees it, with Mitsuba's rectangle coordinates ((x, y) / 2 + 1/2 in its frame)
    and checkerboard rule (color0 where frac(u) and frac(v) fall on the same side of 1/2)."""
    scene = _scene_file(tmp_path, "checker.xml", '''<shape type="rectangle">
        <transform name="to_world"><scale value="10"/></transform>
        <bsdf type="diffuse"><texture name="reflectance" type="checkerboard">
            <rgb name="color0" value="0.8"/><rgb name="color1" value="0.1"/>
            <transform name="to_uv"><scale value="20"/></transform></texture></bsdf></shape>''')
    mean, var = film(scene, seed=4, size=(32, 32))
    half = 5.0 * np.tan(np.radians(20.0))  # the view's half-width on the wall

    def colour(x, y):
        u, v = 20 * (x / 10 + 1) / 2, 20 * (y / 10 + 1) / 2
        return np.where((u % 1 > 0.5) == (v % 1 > 0.5), 0.8, 0.1)

    edges = (np.arange(33) / 32 * 2 - 1) * half
    x0, y0 = np.meshgrid(edges[:-1], -edges[:-1])  # row 0 at the top
    x1, y1 = np.meshgrid(edges[1:], -edges[1:])
    corners = [colour(x, y) for x in (x0, x1) for y in (y0, y1)]
    pure = np.all([c == corners[0] for c in corners], axis=0)  # the pixel sees one square only
    assert pure.sum() > 300 and set(np.unique(corners[0][pure])) == {0.1, 0.8}
    z = (mean[..., 1][pure] - corners[0][pure]) / np.sqrt(np.maximum(var[..., 1][pure], 1e-12))
    level = stats.norm.isf(0.005 / pure.sum())  # two-sided 1% over all tested pixels (Bonferroni)
    assert np.abs(z).max() < level, np.abs(z).max()


def test_crossing_a_null_boundary_is_no_bounce(tmp_path):
    """Direct light only (max_depth 2) on a wall seen through an invisible sphere: the two crossings
    use none of the depth, as in Mitsuba and pbrt, so the wall is lit as without the sphere."""
    wall = '''<shape type="rectangle"><transform name="to_world"><scale value="10"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>'''
    ghost = '<shape type="sphere"><float name="radius" value="1.5"/><bsdf type="null"/></shape>'
    with_ghost = film(_scene_file(tmp_path, "ghost.xml", wall + ghost, size=16), seed=5, size=(16, 16))
    without = film(_scene_file(tmp_path, "plain.xml", wall, size=16), seed=6, size=(16, 16))
    assert with_ghost[0][8, 8, 1] > 0.4  # lit: the crossings did not end the path
    assert_agree(with_ghost, without, ("through a null sphere", "without it"))

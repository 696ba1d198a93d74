"""flip_normals on Mitsuba's analytic sphere and rectangle, rendered: the front side turns over, and
with it what Mitsuba ties to it. Area emitters shine from the front only, so a flipped rectangle
shines from its other side and a flipped sphere inwards (a camera inside sees it, one outside sees
its dark back); a one-sided BSDF is black from behind, so a flipped diffuse rectangle is black
from its former front; back-face culling culls the other side.

Where the answer does not depend on the samples it is exact: emitters seen directly through a box
filter (pixels wholly on the shape), and a diffuse surface under a constant environment traced by
`path` (each sample weighs the albedo). Inside a closed flipped emissive sphere of albedo a the
radiance is Le / (1 - a) everywhere (pbrt's analytic test), which the integrators that sample the
light (from inside: uniform over its area) must reach; z-tests of the image mean. Against Mitsuba 3
where it is installed: its render-test rule per pixel plus the image mean. Significance: ALPHA =
0.01 over the file's NUM_TESTS statistical decisions (Sidak), fixed seeds.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any
from tests.render.mitsuba_xml_compare import lantern_image, mitsuba_image, mitsuba_or_skip
from tests.stats.chi2 import sidak_alpha
from tests.stats.image_tests import assert_agree, mean_z

SIZE = 16
INSIDE = (slice(5, 11), slice(5, 11))  # pixels that see the rectangle only
RADIANCE = (1.0, 2.0, 3.0)
ALPHA = 0.01
FURNACE_INTEGRATORS = ("mis", "nee", "path")
NUM_TESTS = len(FURNACE_INTEGRATORS) + 2 * 2  # image means; two Mitsuba comparisons (pixels, mean)
TEST_ALPHA = sidak_alpha(ALPHA, NUM_TESTS)


def scene_file(tmp_path, name, body, depth=1, camera="0, 0, 5", fov=30, size=SIZE, film=""):
    path = tmp_path / f"{name}.xml"
    path.write_text(f'''<scene version="3.0.0">
        <integrator type="path"><integer name="max_depth" value="{depth}"/></integrator>
        <sensor type="perspective"><float name="fov" value="{fov}"/>
            <transform name="to_world"><lookat origin="{camera}" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><rfilter type="box"/><integer name="width" value="{size}"/>
                <integer name="height" value="{size}"/>{film}</film></sensor>
        {body}</scene>''')
    return path


def render(path, spp=4, integrator=None, seed=1):
    scene = load_any(path)
    renderer = Renderer(scene)
    renderer.render(CameraFrame.from_spec(scene.camera), spp, integrator, seed=seed)
    return renderer.film.mean_image(), renderer.film.variance_of_mean_image()


def flip(value: bool) -> str:
    return f'<boolean name="flip_normals" value="{str(value).lower()}"/>'


EMITTER = '<emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter>'


@pytest.mark.parametrize("flipped", [False, True])
def test_a_flipped_rectangle_emitter_shines_from_its_other_side(tmp_path, flipped):
    body = f'<shape type="rectangle">{flip(flipped)}{EMITTER}</shape>'  # faces +z unless flipped
    front, _ = render(scene_file(tmp_path, "front", body, camera="0, 0, 5"))
    back, _ = render(scene_file(tmp_path, "back", body, camera="0, 0, -5"))
    lit, dark = (back, front) if flipped else (front, back)
    np.testing.assert_array_equal(lit[INSIDE], np.broadcast_to(RADIANCE, lit[INSIDE].shape))
    assert (dark == 0.0).all()


def test_a_flipped_rectangle_emitter_lights_what_its_other_side_faces(tmp_path):
    """An emitter facing up above a floor, seen from below its height: nothing is lit (and its back
    is dark) until it is flipped to face the floor."""
    def image(flipped):
        body = f'''<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/>
                </transform><bsdf type="diffuse"/></shape>
            <shape type="rectangle">{flip(flipped)}<transform name="to_world"><scale value="0.5"/>
                <rotate x="1" angle="-90"/><translate y="1"/></transform>{EMITTER}</shape>'''
        return render(scene_file(tmp_path, f"floor_{flipped}", body, depth=2, camera="0, 0.6, 4", fov=45))[0]
    assert (image(False) == 0.0).all()
    lit = image(True)
    assert (lit[-4:] > 0.0).all()  # the floor's rows (the bottom of the image) are all lit


@pytest.mark.parametrize("flipped", [False, True])
def test_a_one_sided_diffuse_on_a_flipped_rectangle_is_black_from_its_former_front(tmp_path, flipped):
    body = (f'<emitter type="constant"><rgb name="radiance" value="1"/></emitter><shape type="rectangle">'
            f'{flip(flipped)}<bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></shape>')
    # `path` under a constant white sky: every sample of a lit diffuse pixel weighs its albedo.
    front, _ = render(scene_file(tmp_path, "front", body, depth=2, camera="0, 0, 5"), integrator="path")
    back, _ = render(scene_file(tmp_path, "back", body, depth=2, camera="0, 0, -5"), integrator="path")
    lit, dark = (back, front) if flipped else (front, back)
    np.testing.assert_allclose(lit[INSIDE], 0.8, rtol=1e-5)
    assert (dark[INSIDE] == 0.0).all()


SPHERE = '<shape type="sphere"><float name="radius" value="1"/>{flip}{bsdf}' + EMITTER + '</shape>'
BLACK = '<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>'


@pytest.mark.parametrize("flipped", [False, True])
def test_a_flipped_sphere_emitter_shines_inwards(tmp_path, flipped):
    body = SPHERE.format(flip=flip(flipped), bsdf=BLACK)
    inside, _ = render(scene_file(tmp_path, "inside", body, camera="0, 0, 0.5", fov=60))
    outside, _ = render(scene_file(tmp_path, "outside", body, camera="0, 0, 5", fov=10))
    seen, unseen = (inside, outside) if flipped else (outside, inside)
    centre = seen[SIZE // 2 - 2:SIZE // 2 + 2, SIZE // 2 - 2:SIZE // 2 + 2]
    np.testing.assert_array_equal(centre, np.broadcast_to(RADIANCE, centre.shape))
    assert (unseen == 0.0).all()


@pytest.mark.parametrize("integrator", FURNACE_INTEGRATORS)
def test_inside_a_flipped_emissive_sphere_the_radiance_is_le_over_one_minus_albedo(tmp_path, integrator):
    """Light sampling from inside the sphere (uniform over its area, each point emitting towards the
    inside) and BSDF-sampled hits on its emitting side must agree: Le (1 + a + a^2 + ...)."""
    albedo = 0.5
    body = SPHERE.format(flip=flip(True), bsdf=f'<bsdf type="diffuse"><rgb name="reflectance" value="{albedo}"/></bsdf>')
    mean, var = render(scene_file(tmp_path, "furnace", body, depth=-1, camera="0.2, -0.1, 0.3", fov=90), spp=32,
                       integrator=integrator, seed=3)
    expected = RADIANCE[1] / (1.0 - albedo)
    z = mean_z(mean, var, expected)
    assert abs(z) < stats.norm.isf(TEST_ALPHA / 2), (integrator, mean[..., 1].mean(), expected, z)


RECTANGLES = '''
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
        <bsdf type="diffuse"/></shape>
    <!-- faces up, flipped to light the floor -->
    <shape type="rectangle"><boolean name="flip_normals" value="true"/>
        <transform name="to_world"><scale value="0.4"/><rotate x="1" angle="-90"/><translate x="-0.6" y="1"/></transform>
        <emitter type="area"><rgb name="radiance" value="5, 5, 5"/></emitter></shape>
    <!-- mirrored: Mitsuba's normal is to_world's transformed normal, facing down -->
    <shape type="rectangle">
        <transform name="to_world"><scale x="-0.4" y="0.4" z="0.4"/><rotate x="1" angle="90"/><translate x="0.6" y="1"/>
        </transform><emitter type="area"><rgb name="radiance" value="2, 4, 6"/></emitter></shape>
    <!-- a one-sided diffuse card, flipped to face away from the camera -->
    <shape type="rectangle"><boolean name="flip_normals" value="true"/>
        <transform name="to_world"><scale value="0.3"/><translate y="0.4" z="0.5"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.1"/></bsdf></shape>'''
SPHERES = '''
    <shape type="sphere"><float name="radius" value="2"/><boolean name="flip_normals" value="true"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>
    <shape type="sphere"><float name="radius" value="0.5"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.4, 0.2"/></bsdf></shape>
    <!-- mirrored: Mitsuba's sphere then faces inwards, so its light stays inside it -->
    <shape type="sphere"><float name="radius" value="0.3"/><point name="center" x="0.8" y="0" z="0"/>
        <transform name="to_world"><scale x="-1"/></transform>
        <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.8, 0.2"/></bsdf></bsdf>
        <emitter type="area"><rgb name="radiance" value="4, 1, 1"/></emitter></shape>'''


@pytest.mark.parametrize("name, body, depth, camera, fov", [
    ("rectangles", RECTANGLES, 3, "0, 2, 4", 50),
    ("spheres", SPHERES, -1, "0, 0.5, 1.5", 70),
])
def test_flipped_and_mirrored_shapes_render_as_mitsubas(tmp_path, name, body, depth, camera, fov):
    mitsuba_or_skip()
    path = scene_file(tmp_path, name, body, depth=depth, camera=camera, fov=fov)
    assert_agree(lantern_image(path, 256), mitsuba_image(path, 64, 8), ("lantern", "mitsuba"), alpha=TEST_ALPHA)


def test_back_face_culling_culls_the_other_side_of_a_flipped_quad(tmp_path):
    """A culled card (a scene file's sidedness) facing the camera: there; flipped, seen through."""
    path = tmp_path / "cull.toml"
    path.write_text(f'''[scene]
geometry = "mesh"
[camera]
position = [0, 5, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
fov = 30
[render]
width = {SIZE}
height = {SIZE}
[environment]
type = "constant"
color = [1, 1, 1]
[materials.card]
type = "diffuse"
base_color = [0.5, 0.5, 0.5]
sidedness = "back_culled"
[[objects]]
type = "quad"
size = [2, 2]
material = "card"
''')
    scene = load_any(path)
    flipped = replace(scene, mesh_objects=tuple(replace(o, flip_normals=True) for o in scene.mesh_objects))
    for s, see_through in ((scene, False), (flipped, True)):
        renderer = Renderer(s)
        renderer.render(CameraFrame.from_spec(s.camera), 8, "path", max_depth=2)
        inside = renderer.film.mean_image()[INSIDE]
        assert (inside == 1.0).all() if see_through else inside.max() < 0.9

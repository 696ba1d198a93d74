"""A Mitsuba 3 scene file renders: the Cornell box written as Mitsuba XML (tests/data/mitsuba) and
the catalog's TOML Cornell box give statistically equal images (the suite's per-pixel z-test and
image-mean test at the 1% level, independent seeds), and a Mitsuba scene with a homogeneous medium
inside a null-bounded sphere renders with the medium's light loss."""
from __future__ import annotations

import warnings
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
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its Gaussian film filter (tests/scene/mitsuba checks the warning)
        xml = load_any(DATA / "cornell_box.xml")
    toml = load_any(resolve_scene("cornell_box"))
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

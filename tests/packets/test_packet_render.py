"""The packet path renders what the scalar path renders (the suite's per-pixel and image-mean
z-tests, independent seeds), takes the same seed to the same image, and is taken only where
every part of the scene has a packet form, saying why not otherwise."""
from pathlib import Path

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.packets.program import PacketProgram
from renderer.program import RenderProgram
from renderer.renderer import MeshOptions, Renderer
from renderer.scene.catalog import load_any
from tests.stats.image_tests import assert_agree

CORNELL = "assets/scenes/cornell_box.toml"


def render(path, packets, integrator, seed, spp=64, size=(24, 24), max_depth=None):
    scene = load_any(path)
    r = Renderer(scene, size, MeshOptions(packets=packets))
    r.render(CameraFrame.from_spec(scene.camera), spp, integrator=integrator, seed=seed, max_depth=max_depth)
    return r


@pytest.mark.parametrize("integrator", ["mis", "path"])
def test_packets_render_the_scalar_paths_image(integrator):
    scalar = render(CORNELL, 0, integrator, seed=11)
    packed = render(CORNELL, 8, integrator, seed=12)
    program = packed.program(integrator, packed.features(), "independent")
    assert isinstance(program, PacketProgram)
    assert isinstance(scalar.program(integrator, scalar.features(), "independent"), RenderProgram)
    a = (packed.image(), packed.film.variance_of_mean_image())
    b = (scalar.image(), scalar.film.variance_of_mean_image())
    assert b[0].mean() > 0.05
    assert_agree(a, b, ("packets", "scalar"))
    # every lane's samples land on its own pixel: every pixel has its 64
    np.testing.assert_array_equal(packed.film.count.to_numpy()[:24, :24], 64)


def test_packets_with_bounces_one_ray_at_a_time_render_the_scalar_paths_image(monkeypatch):
    """A large world's packets trace their camera rays together and their bounce and shadow rays
    one lane at a time (support.SCALAR_BOUNCE_PRIMITIVES, lowered here to take the Cornell box)."""
    from renderer.packets import support

    monkeypatch.setattr(support, "SCALAR_BOUNCE_PRIMITIVES", 1)
    scalar = render(CORNELL, 0, "mis", seed=51)
    packed = render(CORNELL, 4, "mis", seed=52)
    program = packed.program("mis", packed.features(), "independent")
    assert isinstance(program, PacketProgram) and program.scalar_bounces
    assert_agree((packed.image(), packed.film.variance_of_mean_image()),
                 (scalar.image(), scalar.film.variance_of_mean_image()), ("packets", "scalar"))
    # the work counted is each ray's own walk after the camera rays: per ray, close to the scalar path's
    work_packed, work_scalar = packed.work.to_numpy()[:24, :24], scalar.work.to_numpy()[:24, :24]
    per_ray = [w[..., :2].sum(axis=(0, 1)) / w[..., 2].sum() for w in (work_packed, work_scalar)]
    np.testing.assert_allclose(per_ray[0], per_ray[1], rtol=0.25)


@pytest.mark.parametrize("pixel_filter", ["gaussian", "tent"])
def test_packets_draw_rays_from_the_pixel_filter_as_the_scalar_path_does(pixel_filter):
    """Mitsuba's scenes come with its default Gaussian filter. The glass ball model under the map
    (its only light, which both paths sample alike; both draw the same numbers per decision): the
    same seed gives the same image, every pixel within 1e-3 (relative)."""
    from dataclasses import replace

    images = []
    for packets in (0, 4):
        scene = load_any("tests/data/glass_ball.obj")
        scene = replace(scene, render=replace(scene.render, pixel_filter=pixel_filter))
        r = Renderer(scene, (20, 20), MeshOptions(packets=packets))
        assert isinstance(r.program("mis", r.features()), PacketProgram) == bool(packets)
        r.render(CameraFrame.from_spec(scene.camera), 4, integrator="mis", seed=81)
        images.append(r.image())
    scalar, packed = images
    assert scalar.mean() > 0.1
    relative = np.abs(packed - scalar).max(axis=-1) / np.maximum(np.abs(scalar).max(axis=-1), 1e-3)
    assert (relative < 1e-3).all()


def test_the_same_seed_gives_the_same_image():
    a = render(CORNELL, 8, "mis", seed=5, spp=4, size=(20, 12))
    b = render(CORNELL, 8, "mis", seed=5, spp=4, size=(20, 12))
    np.testing.assert_array_equal(a.image(), b.image())
    # and the work is counted: node visits, primitive tests, rays
    work = a.work.to_numpy()[:20, :12]
    assert (work[..., 2] >= 4).all() and (work[..., 0] > 0).all()
    # and the lanes' occupancy: every sample's camera rays fill their packet's live lanes (30
    # packets of 8 pixels, 4 samples), later traces carry fewer; the rays add up to the work's
    occupancy = a.program("mis", a.features(), "independent").occupancy()
    assert occupancy["closest_traces"] >= 30 * 4 and occupancy["shadow_traces"] > 0
    assert 0.0 < occupancy["shadow"] <= occupancy["closest"] <= 1.0
    closest = occupancy["closest"] * occupancy["closest_traces"] * 8
    shadow = occupancy["shadow"] * occupancy["shadow_traces"] * 8
    assert closest >= 20 * 12 * 4
    assert round(closest + shadow) == round(work[..., 2].sum())


def textured_light_scene(directory: Path) -> Renderer:
    """A rectangle whose emission is an image (Mitsuba's textured area emitter) over a floor."""
    from PIL import Image

    Image.new("RGB", (6, 3), (200, 100, 50)).save(directory / "slide.png")
    path = directory / "slide.xml"
    path.write_text(
        '<scene version="3.0.0">\n<sensor type="perspective"><transform name="to_world"><lookat origin="0, 1, 3" '
        'target="0, 0, 0" up="0, 1, 0"/></transform></sensor>\n'
        '<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/>'
        '</transform><emitter type="area"><texture name="radiance" type="bitmap"><string name="filename" '
        'value="slide.png"/></texture></emitter></shape>\n'
        '<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/></transform>'
        '<bsdf type="diffuse"/></shape>\n</scene>\n')
    return Renderer(load_any(path), (8, 8), MeshOptions(packets=8))


def test_packets_are_taken_only_where_the_scene_has_a_packet_form(tmp_path):
    cornell = Renderer(load_any(CORNELL), (8, 8), MeshOptions(packets=8))
    features = cornell.features()
    assert cornell.packet_reason("mis", features, "independent") is None
    assert "sobol" in cornell.packet_reason("mis", features, "sobol")
    assert "sppm" in cornell.packet_reason("sppm", features, "independent")
    assert not isinstance(cornell.program("sppm", features), PacketProgram)  # sppm keeps its own program
    slide = textured_light_scene(tmp_path)
    assert "textured emission" in slide.packet_reason("mis", slide.features(), "independent")
    assert isinstance(slide.program("mis", slide.features()), RenderProgram)
    with_aovs = Renderer(load_any(CORNELL), (8, 8), MeshOptions(packets=8), aovs=True)
    assert with_aovs.packet_reason("mis", features, "independent") is None
    textured = Renderer(load_any("assets/scenes/textured.toml"), (8, 8), MeshOptions(packets=8), aovs=True)
    assert textured.feature_boost > 0  # textured scenes' AOVs take feature samples
    assert "feature samples" in textured.packet_reason("mis", textured.features(), "independent")
    assert isinstance(textured.program("mis", textured.features()), RenderProgram)
    with pytest.raises(ValueError, match="packets of 3 rays"):
        Renderer(load_any(CORNELL), (8, 8), MeshOptions(packets=3))


def grid_obj(directory: Path, triangles: int) -> Path:
    """A flat grid of `triangles` triangles (two a cell, one row) as an OBJ file."""
    cells = triangles // 2
    xs = np.arange(cells + 1, dtype=np.float64) * 0.01
    vertices = [f"v {x:.4f} 0 {z}" for z in (0.0, 0.01) for x in xs]
    faces = []
    for i in range(cells):
        a, b, c, d = i + 1, i + 2, cells + 2 + i, cells + 3 + i
        faces += [f"f {a} {b} {d}", f"f {a} {d} {c}"]
    path = directory / f"grid{triangles}.obj"
    path.write_text("\n".join(vertices + faces) + "\n")
    return path


def test_large_worlds_trace_bounce_rays_one_lane_at_a_time_and_say_so(tmp_path):
    """From support.SCALAR_BOUNCE_PRIMITIVES on, bounce and shadow rays go one lane at a time
    (a packet's incoherent rays visit more nodes than a ray does), and the status line says so."""
    from renderer.packets import support

    limit = support.SCALAR_BOUNCE_PRIMITIVES
    for triangles, one_at_a_time in ((limit - 2, False), (limit, True)):
        r = Renderer(load_any(grid_obj(tmp_path, triangles)), (8, 8), MeshOptions(packets=4))
        assert r.geometry.primitive_count() == triangles
        status = r.packet_status("mis", r.features(), "independent")
        assert status.startswith("packets of 4 rays: taken")
        assert ("bounce and shadow rays one at a time" in status) == one_at_a_time, status
        assert support.scalar_bounces(r.geometry) == one_at_a_time

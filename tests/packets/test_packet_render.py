"""The packet path renders what the scalar path renders (the suite's per-pixel and image-mean
z-tests, independent seeds), takes the same seed to the same image, and is taken only where
every part of the scene has a packet form, saying why not otherwise."""
import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.packets.program import PacketProgram
from renderer.program import RenderProgram
from renderer.renderer import MeshOptions, Renderer
from renderer.scene.catalog import load_any
from tests.stats.image_tests import assert_agree

CORNELL = "assets/scenes/cornell_box.toml"


def render(path, packets, integrator, seed, spp=64, size=(24, 24)):
    scene = load_any(path)
    r = Renderer(scene, size, MeshOptions(packets=packets))
    r.render(CameraFrame.from_spec(scene.camera), spp, integrator=integrator, seed=seed)
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


def test_packets_are_taken_only_where_the_scene_has_a_packet_form():
    cornell = Renderer(load_any(CORNELL), (8, 8), MeshOptions(packets=8))
    features = cornell.features()
    assert cornell.packet_reason("mis", features, "independent") is None
    assert "sobol" in cornell.packet_reason("mis", features, "sobol")
    assert "sppm" in cornell.packet_reason("sppm", features, "independent")
    assert not isinstance(cornell.program("sppm", features), PacketProgram)  # sppm keeps its own program
    bunnies = Renderer(load_any("assets/scenes/bunnies.toml"), (8, 8), MeshOptions(packets=8))
    reason = bunnies.packet_reason("mis", bunnies.features(), "independent")
    assert "conductor" in reason and "dielectric" in reason
    assert isinstance(bunnies.program("mis", bunnies.features()), RenderProgram)
    with_aovs = Renderer(load_any(CORNELL), (8, 8), MeshOptions(packets=8), aovs=True)
    assert "AOV" in with_aovs.packet_reason("mis", features, "independent")
    with pytest.raises(ValueError, match="packets of 3 rays"):
        Renderer(load_any(CORNELL), (8, 8), MeshOptions(packets=3))

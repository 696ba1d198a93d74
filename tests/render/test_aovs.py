"""Denoising AOVs (renderer/film/aovs.py): in range, equal to the debug views where no delta surface
intervenes, and passed through mirrors and glass to the surface seen in them."""
import numpy as np
import pytest
from scipy import stats

from renderer.film.aovs import DEFAULT_FEATURE_BOOST, FEATURE_BOOSTED_SAMPLES
from renderer.camera import CameraFrame
from renderer.film.pixel_slices import INTERLEAVED, ROUND_SLICES
from renderer.renderer import Renderer
from renderer.scene import load_scene
from renderer.scene.catalog import resolve_scene
from tests.scene_builder import scene_from_toml

ALPHA = 0.001  # significance of the z-tests below


def render_aovs(scene, integrator, spp, seed=7, size=None, renderer=None):
    """A render with AOVs: on `renderer` (reset to `size`) if given, else on a new Renderer."""
    renderer = fresh(renderer, size) if renderer is not None else Renderer(scene, size, aovs=True)
    renderer.render(CameraFrame.from_spec(scene.camera), spp, integrator, seed=seed)
    albedo, normal = renderer.aov_images()
    return renderer, albedo, normal


def render_view(scene, integrator, spp, seed=7, size=None, renderer=None):
    renderer = fresh(renderer, size) if renderer is not None else Renderer(scene, size)
    renderer.render(CameraFrame.from_spec(scene.camera), spp, integrator, seed=seed)
    return renderer.image()


def fresh(renderer, size):
    renderer.reset(*size)
    return renderer


@pytest.fixture(scope="module")
def cornell_box():
    """The Cornell box and two Renderers of it, with and without AOVs, shared by the tests on it:
    each render resets the film to its size (an active region of the 40x40 film), so each
    (integrator, AOVs) kernel compiles once."""
    scene = load_scene(resolve_scene("cornell_box"))
    return scene, Renderer(scene, (40, 40), aovs=True), Renderer(scene, (40, 40))


@pytest.mark.parametrize("name", ["prism", "foggy"])  # dispersion (spectral paths), media (fog, glass)
def test_aovs_are_finite_and_in_range(name):
    scene = load_scene(resolve_scene(name))
    _, albedo, normal = render_aovs(scene, "mis", 2, size=(48, 27))
    assert np.isfinite(albedo).all() and np.isfinite(normal).all()
    assert albedo.min() >= 0.0 and albedo.max() <= 1.0
    assert normal.min() >= -1.0 and normal.max() <= 1.0
    assert albedo.max() > 0.05  # something was written


def test_aovs_equal_the_albedo_and_normals_views_without_delta_surfaces(cornell_box):
    # The Cornell box is all diffuse: the first vertex is the first hit, and the same seed gives the
    # same camera rays, so the running means agree up to float rounding.
    scene, with_aovs, without = cornell_box
    size, spp = (40, 40), 3
    assert with_aovs.feature_boost == 0  # no texture: no feature samples (renderer/film/aovs.py; tests below)
    _, albedo, normal = render_aovs(scene, "mis", spp, size=size, renderer=with_aovs)
    albedo_view = render_view(scene, "albedo", spp, size=size, renderer=without)
    normals_view = render_view(scene, "normals", spp, size=size, renderer=without)
    np.testing.assert_allclose(albedo, np.clip(albedo_view, 0, 1), atol=2e-6)
    # Pixels whose every sample hit one flat wall (a unit mean normal): where some samples miss, the
    # AOV averages in 0 and the normals view a black 0 (not the encoded 0.5).
    hit = np.linalg.norm(normal, axis=2) > 1.0 - 1e-5
    np.testing.assert_allclose(normal[hit] * 0.5 + 0.5, normals_view[hit], atol=2e-6)
    assert hit.mean() > 0.5


def test_debug_views_and_path_without_aovs_keep_their_images(cornell_box):
    # Keeping AOVs changes no colour: the images with and without them are identical.
    scene, with_aovs, without = cornell_box
    render_aovs(scene, "path", 2, size=(24, 24), renderer=with_aovs)
    assert np.array_equal(with_aovs.image(), render_view(scene, "path", 2, size=(24, 24), renderer=without))


PANE_SCENE = """
[scene]
geometry = "mesh"
[camera]
position = [0.5, 0.0, 3.0]
look_at = [0.5, 0.0, 0.0]
fov = 16
[render]
width = 32
height = 32
max_depth = 8
[environment]
type = "constant"
color = [0.0, 0.0, 0.0]
[materials.glass]
type = "dielectric"
base_color = [1.0, 1.0, 1.0]
roughness = 0.0
ior = 1.5
thin = true
[[objects]]
type = "mesh"
file = "{quad}"
{pane}
"""

PANE = """
[[objects]]
type = "quad"
material = "glass"
size = [4.0, 4.0]
rotate = [90.0, 0.0, 0.0]
translate = [0.5, 0.0, 1.5]
"""


def _fresnel_dielectric(cos_i, eta):
    sin_t2 = (1.0 - cos_i**2) / eta**2
    cos_t = np.sqrt(1.0 - sin_t2)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs**2 + rp**2)


def test_glass_pane_passes_the_textured_wall_albedo_through(tmp_path):
    """A thin glass pane in front of a checker-textured wall: each sample's AOV albedo is the wall's
    albedo where the path passes the pane (probability T = 1 - 2F / (1 + F)) and the black
    environment's 0 where it reflects. So E[AOV] = T x (the albedo view without the pane), pixel
    by pixel (a thin pane bends no ray). Tested by a z-test on the pooled ratio, separately on
    the wall's light and dark texels, so the wall's texture must come through."""
    from pathlib import Path

    quad = Path(__file__).resolve().parents[1] / "data" / "textured_quad.glb"
    with_pane = scene_from_toml(tmp_path, PANE_SCENE.format(quad=quad.as_posix(), pane=PANE), "pane")
    without = scene_from_toml(tmp_path, PANE_SCENE.format(quad=quad.as_posix(), pane=""), "wall")
    spp = 48
    # `path`: the tracer writes the AOVs alike under each of its settings, and this one compiles the
    # least (no light sampling; `mis` with AOVs is rendered by the other tests here).
    renderer, albedo, _ = render_aovs(with_pane, "path", spp, seed=3)
    aov_samples = renderer.aovs.state()[2]  # colour and feature samples (renderer/film/aovs.py)
    assert (aov_samples == spp + DEFAULT_FEATURE_BOOST * FEATURE_BOOSTED_SAMPLES).all()
    n = int(aov_samples[0, 0])
    wall = render_view(without, "albedo", spp, seed=3)
    assert wall.max() > 0.0
    # Every camera ray meets the pane within 6 degrees of its normal: T varies by < 1e-4 over the image.
    transmittance = 1.0 - 2.0 * _fresnel_dielectric(1.0, 1.5) / (1.0 + _fresnel_dielectric(1.0, 1.5))
    lum_wall = wall.mean(axis=2)
    lum_aov = albedo.mean(axis=2)
    on_wall = lum_wall > 0.0
    split = np.median(lum_wall[on_wall])
    classes = {"light": on_wall & (lum_wall > split), "dark": on_wall & (lum_wall <= split)}
    assert all(mask.sum() > 50 for mask in classes.values())
    for name, mask in classes.items():
        # Each sample is a Bernoulli(T) multiple of the wall albedo at that ray: the pooled ratio of
        # sums has variance ~ T (1 - T) sum(a^2) / (n sum(a)^2) over the pixels' albedos a, n the
        # AOVs' samples (the wall view's own noise, at 48 spp of a flat texel, is left out).
        a = lum_wall[mask]
        ratio = lum_aov[mask].sum() / a.sum()
        sd = np.sqrt(transmittance * (1 - transmittance) * (a**2).sum() / n) / a.sum()
        z = (ratio - transmittance) / sd
        assert abs(z) < stats.norm.isf(ALPHA / 2), f"{name} texels: AOV / wall = {ratio:.4f}, T = {transmittance:.4f}"
    contrast = lum_wall[classes["light"]].mean() / lum_wall[classes["dark"]].mean()
    assert contrast > 1.5  # (the checker is real, so the two classes test the texture)


MIRROR_SCENE = """
[scene]
geometry = "sdf"
[camera]
position = [0.0, 0.0, 3.0]
look_at = [0.0, 0.0, 0.0]
fov = 20
[render]
width = 24
height = 24
max_depth = 8
[environment]
type = "constant"
color = [0.2, 0.2, 0.2]
[materials.mirror]
type = "conductor"
base_color = [0.9, 0.6, 0.3]
roughness = 0.0
[materials.red]
type = "diffuse"
base_color = [0.8, 0.1, 0.1]
[[objects]]
type = "plane"
material = "mirror"
normal = [0.0, 0.7071068, 0.7071068]
offset = 0.0
[[objects]]
type = "plane"
material = "red"
normal = [0.0, -1.0, 0.0]
offset = -3.0
"""


def test_mirror_passes_the_reflected_surface_albedo_through(tmp_path):
    """A mirror at 45 degrees shows a red ceiling: the AOV albedo is the ceiling's red scaled by the
    mirror's reflectance (its colour, at 45 degrees within Schlick's 0.3% of it), not the mirror's
    own base colour, and the normal is the ceiling's (pointing down)."""
    scene = scene_from_toml(tmp_path, MIRROR_SCENE, "mirror")
    _, albedo, normal = render_aovs(scene, "mis", 4)
    centre = albedo[8:16, 8:16].reshape(-1, 3)
    expected = np.array([0.9, 0.6, 0.3]) * np.array([0.8, 0.1, 0.1])
    np.testing.assert_allclose(centre.mean(axis=0), expected, rtol=0.01, atol=2e-3)
    assert np.allclose(normal[8:16, 8:16].reshape(-1, 3).mean(axis=0), [0.0, -1.0, 0.0], atol=1e-3)


@pytest.mark.parametrize("spp", [3, 11])  # within the boosted first samples, and past them in two launches
def test_feature_samples_fill_the_aovs_and_leave_the_colour_unchanged(cornell_box, spp):
    """Each of a pixel's first FEATURE_BOOSTED_SAMPLES colour samples brings `feature_boost` AOV-only
    samples: the AOVs count them, the colour and its sample counts are bit for bit those of a render
    without them."""
    scene, with_aovs, _ = cornell_box
    camera = CameraFrame.from_spec(scene.camera)
    images, per_launch = {}, with_aovs.samples_per_launch
    for boost in (0, DEFAULT_FEATURE_BOOST):
        with_aovs.feature_boost = boost
        try:
            fresh(with_aovs, (24, 24))
            with_aovs.samples_per_launch = 6  # 11 spp: two launches, the second past the boosted samples
            with_aovs.render(camera, spp, "path", seed=5)
        finally:
            with_aovs.feature_boost = with_aovs.scene_feature_boost
            with_aovs.samples_per_launch = per_launch
        albedo, normal, count = with_aovs.aovs.state()
        assert (count == spp + boost * min(spp, FEATURE_BOOSTED_SAMPLES)).all()
        assert (with_aovs.film.sample_counts() == spp).all()
        images[boost] = with_aovs.image(), albedo
    assert np.array_equal(images[0][0], images[DEFAULT_FEATURE_BOOST][0])
    assert not np.array_equal(images[0][1], images[DEFAULT_FEATURE_BOOST][1])  # the feature samples did add


@pytest.mark.parametrize("name, scene_text", [("pane", None), ("mirror", MIRROR_SCENE)])
def test_feature_samples_see_what_colour_samples_see(tmp_path, name, scene_text):
    """Feature samples end their paths at the first non-delta vertex, so their AOVs must have the
    colour samples' distribution, through a glass pane (Fresnel reflection or transmission drawn
    per sample) and a mirror. AOVs of 64 colour samples against AOVs of 8 colour + 56 feature
    samples, per pixel on independent seeds: the mean of the differences over the image against
    its standard error (a z-test at ALPHA, two-sided), for each channel of albedo and normal."""
    from pathlib import Path

    if scene_text is None:
        quad = Path(__file__).resolve().parents[1] / "data" / "textured_quad.glb"
        scene_text = PANE_SCENE.format(quad=quad.as_posix(), pane=PANE)
    scene = scene_from_toml(tmp_path, scene_text, name)
    renderer = Renderer(scene, (24, 24), aovs=True)
    renderer.feature_boost = 0
    _, colour_albedo, colour_normal = render_aovs(scene, "path", 64, seed=11, size=(24, 24), renderer=renderer)
    renderer.feature_boost = 7
    _, feature_albedo, feature_normal = render_aovs(scene, "path", 8, seed=12, size=(24, 24), renderer=renderer)
    assert (renderer.aovs.state()[2] == 64).all()
    for label, a, b in (("albedo", colour_albedo, feature_albedo), ("normal", colour_normal, feature_normal)):
        for c in range(3):
            d = (a[..., c] - b[..., c]).ravel()
            if d.std() == 0.0:
                assert d.mean() == 0.0
                continue
            z = d.mean() / (d.std(ddof=1) / np.sqrt(d.size))
            assert abs(z) < stats.norm.isf(ALPHA / 2), f"{label}[{c}]: z = {z:.2f}"
    assert colour_albedo.max() > 0.05


def test_only_scenes_with_texture_or_normal_maps_take_feature_samples(tmp_path):
    """Feature samples help where textures put sub-pixel detail into the AOVs; elsewhere they cost
    time for little (renderer/film/aovs.py). A Renderer without AOVs takes none."""
    from pathlib import Path

    quad = Path(__file__).resolve().parents[1] / "data" / "textured_quad.glb"
    textured = scene_from_toml(tmp_path, PANE_SCENE.format(quad=quad.as_posix(), pane=""), "wall")
    plain = load_scene(resolve_scene("cornell_box"))
    assert Renderer(textured, (8, 8), aovs=True).feature_boost == DEFAULT_FEATURE_BOOST
    assert Renderer(textured, (8, 8)).feature_boost == 0
    assert Renderer(plain, (8, 8), aovs=True).feature_boost == 0


def test_the_feature_loop_is_compiled_only_where_feature_samples_are_taken(tmp_path):
    """Unused, the feature-sample loop costs a kernel time (renderer/program.py), so a program has
    it only where the scene takes feature samples, or feature_boost asks for them; a textured
    scene's program keeps it with the boost at 0 (the viewer's denoised-view toggle compiles
    nothing); and a program without it refuses feature samples rather than skip them."""
    from pathlib import Path

    quad = Path(__file__).resolve().parents[1] / "data" / "textured_quad.glb"
    textured = Renderer(scene_from_toml(tmp_path, PANE_SCENE.format(quad=quad.as_posix(), pane=""), "wall"),
                        (8, 8), aovs=True)
    plain = Renderer(load_scene(resolve_scene("cornell_box")), (8, 8), aovs=True)
    features = plain.features()
    assert not plain.program("path", features).feature_samples
    plain.feature_boost = DEFAULT_FEATURE_BOOST
    assert plain.program("path", features).feature_samples
    textured.feature_boost = 0
    assert textured.program("path", textured.features()).feature_samples
    assert not Renderer(load_scene(resolve_scene("cornell_box")), (8, 8)).program("path", features).feature_samples
    plain.feature_boost = 0
    loopless = plain.program("path", features)
    camera = CameraFrame.from_spec(plain.scene.camera)
    with pytest.raises(ValueError, match="feature samples"):
        loopless.render(8, 8, 1, 0, ROUND_SLICES, INTERLEAVED, 1, 4, *camera.kernel_args(), feature_boost=2)

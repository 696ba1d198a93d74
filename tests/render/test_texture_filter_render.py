"""Texture filtering in whole renders: a fine checkerboard to the horizon at 1 spp is closer to
its converged image with mip-mapping than without, and the filtered render converges to the
unfiltered one (the cone narrows as samples accumulate); kernels compile footprints only where a
scene has textures to filter."""
import numpy as np
import pytest
from scipy import stats

from renderer.bench.checker_horizon import checker_horizon
from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any
from renderer.scene.errors import SceneError
from tests.stats.image_tests import assert_agree

SIZE = (64, 32)
ALPHA = 1e-3  # the level of the one-sided tests below


@pytest.fixture(scope="module")
def renderers():
    """One renderer per filter (each render below starts from an empty film)."""
    return {f: Renderer(checker_horizon(f), SIZE) for f in ("none", "trilinear", "anisotropic")}


def render(renderers, texture_filter, spp, seed):
    r = renderers[texture_filter]
    r.reset()
    r.render(CameraFrame.from_spec(r.scene.camera), spp, integrator="path", seed=seed)
    return r.image().copy(), r.film.variance_of_mean_image().copy()


@pytest.fixture(scope="module")
def reference(renderers):
    return render(renderers, "none", 4096, seed=1)[0]


@pytest.mark.parametrize("texture_filter", ["trilinear", "anisotropic"])
def test_filtering_lowers_the_error_of_one_sample_per_pixel(texture_filter, renderers, reference):
    """Per pixel, the squared error of the 1-spp image against the 4096-spp reference, filtered
    minus unfiltered, over four seeds: a one-sided z-test that its mean is below zero."""
    differences = []
    errors = {}
    for seed in (11, 12, 13, 14):
        unfiltered = ((render(renderers, "none", 1, seed)[0] - reference) ** 2).mean(axis=2)
        filtered = ((render(renderers, texture_filter, 1, seed + 100)[0] - reference) ** 2).mean(axis=2)
        differences.append((filtered - unfiltered).ravel())
        errors.setdefault("none", []).append(unfiltered.mean())
        errors.setdefault(texture_filter, []).append(filtered.mean())
    d = np.concatenate(differences)
    z = d.mean() / (d.std(ddof=1) / np.sqrt(d.size))
    rmse = {k: float(np.sqrt(np.mean(v))) for k, v in errors.items()}
    assert stats.norm.cdf(z) < ALPHA, f"z = {z:.2f}, RMSE {rmse}"
    assert rmse[texture_filter] < 0.8 * rmse["none"], rmse


@pytest.mark.parametrize("texture_filter", ["trilinear", "anisotropic"])
def test_the_filtered_render_converges_to_the_unfiltered_one(texture_filter, renderers):
    assert_agree(render(renderers, texture_filter, 256, seed=3), render(renderers, "none", 256, seed=4),
                 (texture_filter, "none"))


def test_footprints_are_compiled_only_where_textures_are_filtered():
    def filters(scene):
        r = Renderer(scene, (8, 8))
        return r.program("mis", r.features(), "independent").filters_textures

    assert filters(checker_horizon("trilinear")) and filters(checker_horizon("anisotropic"))
    assert not filters(checker_horizon("none"))
    assert not filters(load_any("assets/scenes/cornell_box.toml"))  # no textures: nothing to filter


def test_an_unknown_filter_in_a_scene_file_is_one_line_naming_it(tmp_path):
    path = tmp_path / "bicubic.toml"
    path.write_text('[scene]\nname = "x"\ngeometry = "mesh"\n[render]\ntexture_filter = "bicubic"\n'
                    '[materials.m]\ntype = "diffuse"\n[[objects]]\ntype = "quad"\nmaterial = "m"\n')
    with pytest.raises(SceneError) as error:
        load_any(str(path))
    message = str(error.value)
    assert "\n" not in message and "bicubic.toml" in message and "texture_filter" in message, message
    assert "anisotropic" in message


def test_sppm_narrows_its_texture_cones_and_keeps_its_photon_radius():
    """SPPM's camera pass narrows its rays' cones with the iteration, as camera samples do, and
    sizes its visible points' footprints (which set their photon radii) from the whole pixel's
    cone still: after three iterations (the cone at 1/sqrt(3)) the footprints are those of the
    unfiltered render, whose cones never narrow."""
    footprints = {}
    for texture_filter in ("none", "anisotropic"):
        scene = checker_horizon(texture_filter)
        r = Renderer(scene, (32, 16))
        r.render(CameraFrame.from_spec(scene.camera), 3, integrator="sppm", seed=5)
        assert r.program("sppm", r.features(), "independent").filters_textures == (texture_filter != "none")
        footprints[texture_filter] = r.shared("sppm_state", None).footprint.to_numpy()[:32, :16]
    assert (footprints["none"] > 0).mean() > 0.5  # the floor's visible points
    np.testing.assert_allclose(footprints["anisotropic"], footprints["none"], rtol=1e-5)

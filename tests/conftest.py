import pytest
import taichi as ti

from renderer.runtime import taichi_frontend
from renderer.runtime.arch import cpu_scheduling_options, offline_cache_options, taichi_options


@pytest.fixture(scope="module", autouse=True)
def taichi_runtime():
    """A fresh Taichi runtime per test module (never at import time).

    Every field a test allocates lives until the runtime is reset, and one runtime holds a bounded
    number of field trees: a whole suite in one runtime exhausts it (a crash inside Taichi). A reset
    per module frees them; compiled kernels come back from the offline cache. Kernels are
    optimised for compile time: a clean checkout compiles every kernel of the suite afresh.
    """
    taichi_frontend.install()  # as init_taichi does: cheaper compiles
    ti.init(arch=ti.cpu, random_seed=0, **offline_cache_options(), **taichi_options("compile"),
            **cpu_scheduling_options())
    yield
    ti.reset()


# The longest test files run first. Whole files go to a worker (--dist loadfile) in collection
# order, and tests/viewer comes last alphabetically: its offscreen window file (every catalog scene
# compiled) then ran alone at the end while the other core idled. Longest first shortens the run.
LONGEST_FILES = (  # a cold run's order (clean offline cache, as in CI)
    "tests/commands/distributed/test_ray_render.py",
    "tests/packets/test_packet_shading.py",
    "tests/viewer/test_window_offscreen.py",
    "tests/render/test_glass_furnace.py",
    "tests/render/test_integrator_agreement.py",
    "tests/test_vulkan.py",
    "tests/materials/test_bsdf_chi2.py",
    "tests/render/test_sppm.py",
    "tests/geometry/test_wide_bvh.py",
    "tests/geometry/test_traversal.py",
)


# The full tier (`bash scripts/test.sh --full`; the default run leaves these out, marked slow).
# Each costs 10-100 s on a clean machine, mostly compiling a kernel of its own, and repeats a
# property a default test holds on another case: the default run stays near 15 minutes on 2 cores.
FULL_TIER = (
    # packets through every material, map and AOV case (default: textures at depth 2, glass AOVs)
    "tests/packets/test_packet_shading.py::test_packets_render_every_material_as_the_scalar_path_does",
    "tests/packets/test_packet_shading.py::test_packets_render_shading_normals_as_the_scalar_path_does",
    "tests/packets/test_packet_shading.py::test_packets_render_a_map_environment_as_the_scalar_path_does",
    "tests/packets/test_packet_shading.py::test_packets_render_textures_and_normal_maps_as_the_scalar_path_does"
    "[8-0.97]",
    "tests/packets/test_packet_shading.py::test_packets_write_the_denoisers_aovs_as_the_scalar_path_does[materials-8]",
    "tests/packets/test_packet_shading.py::test_packets_write_the_denoisers_aovs_as_the_scalar_path_does[materials-1]",
    "tests/packets/test_packet_render.py::test_packets_draw_rays_from_the_pixel_filter_as_the_scalar_path_does[tent]",
    # emissive spheres seen from inside (default: from outside; the inside branch's lanes alone)
    "tests/packets/test_packet_sphere_lights.py::test_packets_sample_emissive_spheres_as_the_scalar_path_does[inside]",
    # the furnace under every integrator and glass (default: path, the shapes, SPPM's smooth glass)
    "tests/render/test_glass_furnace.py::test_every_white_glass_is_invisible_in_the_furnace[nee]",
    "tests/render/test_glass_furnace.py::test_every_white_glass_is_invisible_in_the_furnace[mis]",
    "tests/render/test_glass_furnace.py::test_white_glass_is_invisible_in_the_furnace_through_packets",
    "tests/render/test_glass_furnace.py::test_smooth_glass_under_nee_in_a_furnace_of_its_own",
    "tests/render/test_glass_furnace.py::test_sppm_keeps_the_light_of_thin_rough_glass",
    "tests/render/test_glass_furnace.py::test_thin_walls_keep_the_light_inside_too",
    # the viewer on the heaviest catalog scenes (default: the others)
    "tests/viewer/test_window_offscreen.py::test_each_scene_shows_the_film[textured]",
    "tests/viewer/test_window_offscreen.py::test_each_scene_shows_the_film[studio]",
    "tests/viewer/test_window_offscreen.py::test_each_scene_shows_the_film[bunnies]",
    "tests/viewer/test_window_offscreen.py::test_each_scene_shows_the_film[stress]",
    "tests/viewer/test_window_offscreen.py::test_each_scene_shows_the_film[many_lights]",
    # traversal variants on the textured scene (default: the other scenes)
    "tests/geometry/test_triangle_packets.py::test_mesh_scene_renders_z_equal_to_the_scalar_leaves"
    "[assets/scenes/textured.toml]",
    "tests/geometry/test_wide_bvh.py::test_mesh_scene_renders_z_equal_to_the_binary_traversal"
    "[assets/scenes/textured.toml]",
    # second cases of one property
    "tests/lights/test_delta_lights.py::test_all_lights_render_the_sum_of_each_alone[power]",
    "tests/render/test_aovs.py::test_feature_samples_see_what_colour_samples_see[pane-None]",
    "tests/render/test_model_material_edits.py::test_a_picked_model_material_is_edited_by_its_panel_and_saved_beside"
    "_the_model",
    "tests/render/test_model_material_edits.py::test_a_toml_scenes_model_material_edits_are_saved_in_its_copy",
    "tests/materials/test_principled_layers.py::test_white_layers_keep_their_energy[all over metal]",
    "tests/test_vulkan.py::test_vulkan_runs_media_and_dispersion[goblet]",
    "tests/test_vulkan.py::test_vulkan_runs_media_and_dispersion[prism]",
    # Mitsuba's agreement on textured materials (default: principled, the blend, the pbrt rooms)
    "tests/commands/test_compare.py::test_textured_anisotropic_roughness_agrees_with_mitsuba",
    "tests/commands/test_compare.py::test_textured_principled_agrees_with_mitsuba[principledthin]",
    "tests/commands/test_compare.py::test_textured_specular_tints_agree_with_mitsuba",
    "tests/render/test_crop_render.py::test_a_crop_is_the_same_window_of_the_whole_render_bit_for_bit[tent]",
    "tests/render/test_crop_render.py::test_a_crop_is_the_same_window_of_the_whole_render_bit_for_bit[box]",
    "tests/render/test_material_edits.py::test_an_emission_edit_reweighs_the_lights_in_place[sppm]",
    "tests/render/test_texture_filter_render.py::test_sppm_narrows_its_texture_cones_and_keeps_its_photon_radius",
    # the benchmarks' tiny runs that compile builds of their own (their figures come from the benchmarks)
    "tests/bench/test_bench_features.py::test_run_on_a_tiny_scene",
    "tests/bench/test_bench_denoise.py::test_tiny_run_writes_curves_targets_and_a_plot",
    "tests/bench/test_bench_photons.py::test_runs_on_a_tiny_glass_scene",
    "tests/commands/distributed/test_ray_render.py::test_bench_scale_on_a_tiny_image",
    "tests/bench/test_bench_scenes.py::test_the_mitsuba_side_renders_what_converts_and_says_why_not_otherwise",
)


def mark_full_tier(items):
    """Mark FULL_TIER's tests slow; a name there that its collected file no longer has is an error
    (a renamed test would otherwise drop back into the default run unnoticed)."""
    ids = {item.nodeid: item for item in items}
    files = {nodeid.split("::")[0] for nodeid in ids}
    stale = [name for name in FULL_TIER if name.split("::")[0] in files and name not in ids]
    if stale:
        raise pytest.UsageError(f"tests/conftest.py FULL_TIER names tests that do not exist: {stale}")
    for name in FULL_TIER:
        if name in ids:
            ids[name].add_marker(pytest.mark.slow)


def pytest_collection_modifyitems(items):
    mark_full_tier(items)
    rank = {path: i for i, path in enumerate(LONGEST_FILES)}
    # A stable sort: the other files, and the tests within every file, keep their order.
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))

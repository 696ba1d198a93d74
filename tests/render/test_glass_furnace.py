"""Glass keeps its light: white furnaces of every transmissive configuration, whole scenes.

A closed, non-absorbing, white dielectric solid in a constant environment of radiance 1 must look
exactly 1 from outside, whatever its shape, roughness or index, and n^2 from inside it (radiance
over n^2 is what is conserved across an interface: a sensor immersed in glass sees n^2). The frame
is filled by the solid, so every pixel tests it.

The per-lobe tests (chi-square of the sampler against its pdf, reciprocity, weights against the
integral of eval) could not see that rough glass lost a fifth of its light: each checks that a
lobe is sampled and evaluated *consistently*, not that the lobe returns all the energy it should.
A single-scattering microfacet interface consistently drops the light that meets more than one
microfacet (0.82 for a white glass ball of roughness 0.5, 0.36 at roughness 1). Only an energy
balance over the whole solid, where every crossing and every internal reflection enters, tests
what a user sees; these tests are that balance.

Decision rule: the image mean (green; the channels of a grey scene are the same numbers) against
the exact value by a z-test with the film's per-pixel variance of the mean, pixels independent, at
ALPHA = 0.01 Sidak-corrected over every test of this module. What the compensation leaves is the
error of its interpolated tables (below 3e-4 where tested in tests/materials), a tenth of the
standard errors here. SPPM keeps no variance (its image is not a mean of samples): it is rendered
with SEEDS independent seeds and their image means are t-tested against the exact value.
"""
import numpy as np
import pytest
import trimesh
from scipy import stats

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from tests.scene_builder import scene_from_toml
from tests.stats.chi2 import sidak_alpha
from tests.stats.image_tests import mean_z

ALPHA = 0.01
IOR = 1.5
SIZE = int(__import__("os").environ.get("FURNACE_SIZE", 16))
SPP = 128
SEEDS = 3

HEADER = """
[scene]
geometry = "{geometry}"
[camera]
position = {position}
look_at = {look_at}
fov = {fov}
[render]
width = {size}
height = {size}
max_depth = -1
[environment]
type = "constant"
color = [1.0, 1.0, 1.0]
[materials.glass]
{material}
"""

MATERIALS = {
    "smooth": f'type = "dielectric"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.0\nior = {IOR}',
    "rough0.3": f'type = "dielectric"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.3\nior = {IOR}',
    "rough1.0": f'type = "dielectric"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 1.0\nior = {IOR}',
    "dense2.4": 'type = "dielectric"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.5\nior = 2.4',
    "principled-smooth": ('type = "principled"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.0\nmetallic = 0.0\n'
                          f'transmission = 1.0\nior = {IOR}'),
    "principled-rough": ('type = "principled"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.6\nmetallic = 0.0\n'
                         f'transmission = 1.0\nior = {IOR}'),
    "thin-smooth": 'type = "dielectric"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.0\nthin = true',
    "thin-rough": 'type = "dielectric"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.6\nthin = true',
    "principled-thin": ('type = "principled"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.4\nmetallic = 0.0\n'
                        'transmission = 1.0\nthin = true'),
    # Layers over glass: a clear coat and a sheen over a rough glass lobe.
    "principled-layered": ('type = "principled"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.5\nmetallic = 0.0\n'
                           f'transmission = 1.0\nior = {IOR}\nclearcoat = 1.0\nclearcoat_roughness = 0.2\n'
                           'sheen_color = [1.0, 1.0, 1.0]\nsheen_roughness = 0.5'),
    # Half glass, half a white diffuse base under a clear coat: the layering must lose nothing either.
    "principled-half": ('type = "principled"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.4\nmetallic = 0.0\n'
                        f'transmission = 0.5\nior = {IOR}'),
}

# (material, integrator) on the analytic sphere of a mesh scene, camera outside.
INTEGRATOR_CASES = [(m, i) for m in ("smooth", "rough0.3", "rough1.0", "principled-rough", "principled-half")
                    for i in ("path", "nee", "mis")] + [("dense2.4", "mis"), ("principled-smooth", "mis")]
# (geometry, camera inside?) with rough glass and mis.
SHAPE_CASES = [("analytic_sphere", False), ("analytic_sphere", True), ("mesh_ccw", False), ("mesh_cw", False),
               ("mesh_ccw", True), ("mesh_cw", True), ("sdf_sphere", False), ("sdf_sphere", True),
               ("thin_plate_mesh", False), ("thin_plate_sdf", False)]
SPPM_CASES = ["smooth", "rough0.3", "thin-rough"]
# Thin walls have no inside: the sphere's inside is the outside medium, radiance 1 on both sides.
THIN_CASES = [(m, inside) for m in ("thin-smooth", "thin-rough", "principled-thin") for inside in (False, True)]
LAYER_CASES = ["principled-layered"]
NUM_TESTS = len(INTEGRATOR_CASES) + len(SHAPE_CASES) + len(SPPM_CASES) + len(THIN_CASES) + len(LAYER_CASES)
LEVEL = sidak_alpha(ALPHA, NUM_TESTS)


def _vec(v):
    return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"


def furnace_scene(tmp_path, shape, material, inside=False):
    """A white solid filling the frame of a SIZE x SIZE camera (or the camera at its centre)."""
    geometry = "sdf" if shape.startswith("sdf") or shape == "thin_plate_sdf" else "mesh"
    position, look_at, fov = (0.0, 0.0, 3.0), (0.0, 0.0, 0.0), 15.0  # sees +-0.39 m at the origin
    if inside:
        position, look_at, fov = (0.0, 0.02, 0.01), (0.3, -0.1, -1.0), 60.0
    if shape.startswith("thin_plate"):
        position, look_at, fov = (0.1, 0.2, 3.0), (0.0, 0.0, 0.0), 15.0  # through a 2 mm plate at an angle
    body = HEADER.format(geometry=geometry, position=_vec(position), look_at=_vec(look_at), fov=fov, size=SIZE,
                         material=MATERIALS[material])
    if shape in ("analytic_sphere", "sdf_sphere"):
        body += '[[objects]]\ntype = "sphere"\nmaterial = "glass"\nradius = 0.5\n'
    elif shape == "thin_plate_sdf":
        body += '[[objects]]\ntype = "box"\nmaterial = "glass"\nsize = [1.2, 1.2, 0.002]\nrotate = [10.0, 20.0, 0.0]\n'
    else:
        if shape == "thin_plate_mesh":
            mesh = trimesh.creation.box(extents=(1.2, 1.2, 0.002))
            mesh.apply_transform(trimesh.transformations.euler_matrix(np.radians(10.0), np.radians(20.0), 0.0))
        else:
            mesh = trimesh.creation.icosphere(subdivisions=3, radius=0.5)
        path = tmp_path / f"{shape}.obj"
        if shape == "mesh_cw":
            # Wound clockwise seen from outside, with outward per-face normals: the file says
            # where outside is by its normals, against its winding (the loader rewinds). The
            # normals are the faces' own, so shading is flat and no shading-normal rule ends paths
            # (that loss is tested with smooth normals in test_mesh_render.py).
            write_obj_with_face_normals(path, mesh.vertices, mesh.faces[:, ::-1], mesh.face_normals)
        else:
            mesh.export(path, include_normals=False)  # flat: the true surface, as above
        body += f'[[objects]]\ntype = "mesh"\nfile = "{path.name}"\nmaterial = "glass"\n'
    return scene_from_toml(tmp_path, body, name=f"{shape}_{material}")


def write_obj_with_face_normals(path, vertices, faces, normals):
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in vertices]
    lines += [f"vn {x:.9g} {y:.9g} {z:.9g}" for x, y, z in normals]
    lines += [f"f {a + 1}//{k + 1} {b + 1}//{k + 1} {c + 1}//{k + 1}" for k, (a, b, c) in enumerate(faces)]
    path.write_text("\n".join(lines) + "\n")


def render(scene, integrator, spp=SPP, seed=0):
    r = Renderer(scene)
    r.render(CameraFrame.from_spec(scene.camera), spp, integrator=integrator, seed=seed)
    assert r.film.stats()["rejected"] == 0
    return r


# Smooth glass in a furnace is nearly deterministic: most paths return exactly 1 up to f32 rounding
# of their weight, a product of a few dozen factors each rounded to 2^-24 relative. That rounding
# is added to the sampling variance, so that a pixel all of whose paths agree is not held to
# zero error.
ROUNDING = 1e-5


def assert_furnace(r, expected, what):
    mean = r.film.mean_image()
    var = r.film.variance_of_mean_image() + (ROUNDING * expected) ** 2
    z = mean_z(mean, var, expected)
    p = 2.0 * stats.norm.sf(abs(z))
    assert p >= LEVEL, f"{what}: image mean {mean[..., 1].mean():.5f}, expected {expected}, z = {z:.2f}"


@pytest.mark.parametrize("material,integrator", INTEGRATOR_CASES, ids=[f"{m}-{i}" for m, i in INTEGRATOR_CASES])
def test_white_glass_sphere_is_invisible_in_the_furnace(tmp_path, material, integrator):
    r = render(furnace_scene(tmp_path, "analytic_sphere", material), integrator)
    assert_furnace(r, 1.0, f"{material} with {integrator}")


@pytest.mark.parametrize("shape,inside", SHAPE_CASES, ids=[f"{s}-{'inside' if i else 'outside'}"
                                                           for s, i in SHAPE_CASES])
def test_every_shape_keeps_the_light_from_both_sides(tmp_path, shape, inside):
    r = render(furnace_scene(tmp_path, shape, "rough0.3", inside), "mis")
    assert_furnace(r, IOR * IOR if inside else 1.0, f"{shape}, camera {'inside' if inside else 'outside'}")


@pytest.mark.parametrize("material", SPPM_CASES)
def test_sppm_keeps_the_light(tmp_path, material):
    scene = furnace_scene(tmp_path, "analytic_sphere", material)
    r = Renderer(scene)  # one renderer for every seed: its programs compile once
    means = []
    for seed in range(1, SEEDS + 1):
        r.reset()
        r.render(CameraFrame.from_spec(scene.camera), 32, integrator="sppm", seed=seed)
        means.append(r.image()[..., 1].mean())
    t, p = stats.ttest_1samp(means, 1.0)
    assert p >= LEVEL, f"sppm {material}: image means {np.round(means, 5)}, t = {t:.2f}"


@pytest.mark.parametrize("material,inside", THIN_CASES, ids=[f"{m}-{'inside' if i else 'outside'}" for m, i in THIN_CASES])
def test_thin_walls_keep_the_light_from_both_sides(tmp_path, material, inside):
    r = render(furnace_scene(tmp_path, "analytic_sphere", material, inside), "mis")
    assert_furnace(r, 1.0, f"{material}, camera {'inside' if inside else 'outside'}")


@pytest.mark.parametrize("material", LAYER_CASES)
def test_layers_over_glass_keep_the_light(tmp_path, material):
    r = render(furnace_scene(tmp_path, "analytic_sphere", material), "mis")
    assert_furnace(r, 1.0, material)

"""Glass keeps its light: white furnaces of every transmissive configuration, whole scenes.

A closed, non-absorbing, white dielectric solid in a constant environment of radiance 1 must look
exactly 1 from outside, whatever its shape, roughness or index, and n^2 from inside it (radiance
over n^2 is what is conserved across an interface: a sensor immersed in glass sees n^2).

The per-lobe tests (chi-square of the sampler against its pdf, reciprocity, weights against the
integral of eval) could not see that rough glass lost a fifth of its light: each checks that a
lobe is sampled and evaluated *consistently*, not that the lobe returns all the energy it should.
A single-scattering microfacet interface consistently drops the light that meets more than one
microfacet (0.82 for a white glass ball of roughness 0.5, 0.36 at roughness 1). Only an energy
balance over the whole solid, where every crossing and every internal reflection enters, tests
what a user sees; these tests are that balance.

Every object stands in one furnace with others (a grid of solids, one per cell, seen head-on by a
distant camera): a closed lossless scene is exactly 1 everywhere whatever else it holds, so each
cell tests its own solid, and one renderer (one compile per integrator) tests them all. Views from
inside a solid use the same renderer with another camera.

Decision rule: per solid, the mean of the green channel over the pixels well inside its silhouette
against the exact value, by a z-test with the film's per-pixel variance of the mean, pixels
independent, at ALPHA = 0.01 Sidak-corrected over every decision of this module. What the
compensation leaves is the error of its interpolated tables (below 3e-4 where tested in
tests/materials), a tenth of the standard errors here.

SPPM keeps no variance (its image is not a mean of samples): each solid is rendered with many
independent seeds and its mean over them t-tested against the exact value, at the same
per-decision level, with the power to see a loss: enough seeds for a mean 1 % low (0.99 of the
exact value or less) to fail with probability 0.99. Each decision checks its own standard error
against that need, so a spread larger than planned fails rather than letting a loss pass unseen
(thin rough glass has that power in a furnace of its own; in the grid, beside the smooth ball's
caustics, it is t-tested without it, as a check for gross losses). SPPM is consistent, not
unbiased: its density estimate over a radius moves light about. Where the light comes by the
camera pass (smooth and rough 0.3 glass: traced through) that is within 0.1 %, about one standard
error here; thin rough glass, the one solid that holds visible points,
sat 0.23 % low at its settings here (-0.234 +- 0.032 % over 1500 seeds), so its mean fails when it
lies more than SPPM_BIAS = 0.3 % from the exact value beyond the t-test's margin (a plain t-test
with the power above would fail a correct renderer about one time in fifteen).
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
CELL = 28  # pixels across a cell of the grid
SPACING = 1.2  # metres between neighbouring solids' centres (radius 0.5: gaps between them)
CAMERA_DISTANCE = 20.0  # far: the grid's plane maps almost orthographically, cell by cell
MASK_RADIUS = 0.35  # metres around a solid's centre whose pixels test it (silhouette: 0.5)
SPP = 128
# SPPM: the grid's solids (their light reaches them by the camera pass) and thin rough glass in a
# furnace of its own (its light comes by photons: SPPM_PHOTONS of them a pixel, its whole disc in
# the mean, SPPM_MASK_RADIUS). Next to the smooth ball's caustics it would need several times the
# photons: in the grid it is t-tested as before, a check for gross losses. Spread of the seeds'
# means, measured: rough 0.3 in the grid sd 0.0055 (32 iterations), thin rough alone 0.0122 (8
# iterations): the seeds below give each decision the standard error its power needs with a
# margin (t's critical value counted).
SPPM_GRID_SEEDS, SPPM_GRID_ITERATIONS = 30, 32
SPPM_ALONE_SEEDS, SPPM_ALONE_ITERATIONS, SPPM_PHOTONS, SPPM_MASK_RADIUS = 160, 8, 64, 0.48
SPPM_BIAS = 0.003  # thin rough glass's SPPM bias at its settings is within this (see above)
SPPM_LOSS = 0.01  # a loss of light each SPPM decision must see ...
SPPM_POWER = 0.99  # ... with this probability

HEADER = """
[scene]
geometry = "{geometry}"
[camera]
position = [0.0, 0.0, {distance}]
look_at = [0.0, 0.0, 0.0]
fov = {fov:.9g}
[render]
width = {width}
height = {height}
max_depth = -1
[environment]
type = "constant"
color = [1.0, 1.0, 1.0]
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

# The material grid: every glass, rendered by every integrator (4 columns x 3 rows, one empty).
# No lobe much narrower than roughness 0.3: `nee` light-samples such a lobe (it is not a delta),
# which almost never finds it; its estimate is unbiased but so heavy-tailed (roughness 0.1: cell
# means 0.17 at 64 spp, 0.93 at 16384) that no z-test on its sample variance holds, and it reaches
# every neighbouring solid's image through their reflections.
GRID_MATERIALS = ["smooth", "rough0.3", "rough1.0", "dense2.4", "principled-smooth",
                  "principled-rough", "principled-half", "principled-layered", "thin-smooth", "thin-rough",
                  "principled-thin"]
GRID_COLUMNS = 4
INTEGRATORS = ["path", "nee", "mis"]
# Glass with no rough part. Under `nee` the smooth solids of the grid see their rough neighbours
# through nearly deterministic paths, and a rough lobe's light-sampled estimate is heavy-tailed
# (most samples miss the lobe): in the few paths that reach a neighbour it came out 0.1 % low at
# z = -4.4 against the near-zero variance of the rest. Under `nee` they stand in a furnace of their
# own, where each still shows that light reached after a delta bounce counts.
DELTA_MATERIALS = ["smooth", "principled-smooth", "thin-smooth"]
THIN = ["thin-smooth", "thin-rough", "principled-thin"]  # no inside: radiance 1 within them too
# The shape rows, rough glass, mis: every way a solid reaches the renderer, seen from outside and
# (closed solids) from inside.
MESH_SHAPES = ["analytic_sphere", "mesh_ccw", "mesh_cw", "thin_plate_mesh"]
SDF_SHAPES = ["sdf_sphere", "thin_plate_sdf"]
CLOSED = {"analytic_sphere", "mesh_ccw", "mesh_cw", "sdf_sphere"}
SPPM_MATERIALS = ["smooth", "rough0.3", "thin-rough"]

# (under nee the delta glasses are decided in their own furnace instead of the grid: no extra count)
NUM_DECISIONS = (len(INTEGRATORS) * len(GRID_MATERIALS) + len(THIN) + len(MESH_SHAPES) + len(SDF_SHAPES)
                 + len(CLOSED) + len(SPPM_MATERIALS) + 1)  # (+ thin rough glass's own SPPM furnace)
LEVEL = sidak_alpha(ALPHA, NUM_DECISIONS)


def _vec(v):
    return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"


class Grid:
    """Cells of SPACING metres in the plane z = 0, row 0 at the top, seen whole by the camera."""

    def __init__(self, count, columns):
        self.columns, self.rows = columns, -(-count // columns)
        self.width, self.height = self.columns * CELL, self.rows * CELL
        # vertical field of view spanning the rows exactly at the plane
        self.fov = float(np.degrees(2.0 * np.arctan(0.5 * self.rows * SPACING / CAMERA_DISTANCE)))

    def centre(self, index):
        row, column = divmod(index, self.columns)
        return ((column - 0.5 * (self.columns - 1)) * SPACING, (0.5 * (self.rows - 1) - row) * SPACING, 0.0)

    def mask(self, index, radius=MASK_RADIUS):
        """The pixels whose centres lie within `radius` of cell `index`'s centre."""
        x0, y0, _ = self.centre(index)
        per_pixel = SPACING / CELL
        xs = (np.arange(self.width) + 0.5 - 0.5 * self.width) * per_pixel
        ys = (0.5 * self.height - np.arange(self.height) - 0.5) * per_pixel  # row 0 = top
        return (xs[None, :] - x0) ** 2 + (ys[:, None] - y0) ** 2 < radius**2

    def header(self, geometry):
        return HEADER.format(geometry=geometry, distance=CAMERA_DISTANCE, fov=self.fov, width=self.width,
                             height=self.height)


def material_block(name):
    return f'[materials."{name}"]\n{MATERIALS[name]}\n'


def shape_object(tmp_path, shape, material, centre):
    """The TOML of one solid centred at `centre`."""
    at = f"translate = {_vec(centre)}\n"
    if shape in ("analytic_sphere", "sdf_sphere"):
        return f'[[objects]]\ntype = "sphere"\nmaterial = "{material}"\nradius = 0.5\n{at}'
    if shape == "thin_plate_sdf":  # a 2 mm plate at an angle
        return (f'[[objects]]\ntype = "box"\nmaterial = "{material}"\nsize = [1.0, 1.0, 0.002]\n'
                f'rotate = [10.0, 20.0, 0.0]\n{at}')
    if shape == "thin_plate_mesh":
        mesh = trimesh.creation.box(extents=(1.0, 1.0, 0.002))
        mesh.apply_transform(trimesh.transformations.euler_matrix(np.radians(10.0), np.radians(20.0), 0.0))
    else:
        mesh = trimesh.creation.icosphere(subdivisions=3, radius=0.5)
    path = tmp_path / f"{shape}.obj"
    if shape == "mesh_cw":
        # Wound clockwise seen from outside, with outward per-face normals: the file says where
        # outside is by its normals, against its winding (the loader rewinds). The normals are the
        # faces' own, so shading is flat and no shading-normal rule ends paths (that loss is tested
        # with smooth normals in test_mesh_render.py).
        write_obj_with_face_normals(path, mesh.vertices, mesh.faces[:, ::-1], mesh.face_normals)
    else:
        mesh.export(path, include_normals=False)  # flat: the true surface, as above
    return f'[[objects]]\ntype = "mesh"\nfile = "{path.name}"\nmaterial = "{material}"\n{at}'


def write_obj_with_face_normals(path, vertices, faces, normals):
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in vertices]
    lines += [f"vn {x:.9g} {y:.9g} {z:.9g}" for x, y, z in normals]
    lines += [f"f {a + 1}//{k + 1} {b + 1}//{k + 1} {c + 1}//{k + 1}" for k, (a, b, c) in enumerate(faces)]
    path.write_text("\n".join(lines) + "\n")


def furnace_grid(tmp_path, geometry, cells, columns, name):
    """A furnace holding one solid per cell: `cells` lists (shape, material) pairs."""
    grid = Grid(len(cells), columns)
    body = grid.header(geometry) + "".join(material_block(m) for m in sorted({m for _, m in cells}))
    body += "".join(shape_object(tmp_path, shape, material, grid.centre(i)) for i, (shape, material) in enumerate(cells))
    return grid, scene_from_toml(tmp_path, body, name=name)


def inside_camera(centre):
    """A camera just off a solid's centre, looking along no axis: it sees only the solid's inside."""
    x, y, z = centre
    return CameraFrame.look_at((x, y + 0.02, z + 0.01), (x + 0.3, y - 0.1, z - 1.0), fov=60.0)


def render(r, integrator, camera=None, spp=SPP, seed=0):
    r.reset()
    r.render(camera or CameraFrame.from_spec(r.scene.camera), spp, integrator=integrator, seed=seed)
    assert r.film.stats()["rejected"] == 0
    return r


# Smooth glass in a furnace is nearly deterministic: most paths return exactly 1 up to f32 rounding
# of their weight, a product of a few dozen factors each rounded to 2^-24 relative. That rounding
# is added to the sampling variance, so that a pixel all of whose paths agree is not held to
# zero error.
ROUNDING = 1e-5


def furnace_failure(r, expected, what, mask=None, level=LEVEL):
    """None if the pixels of `mask` (all by default) pass the z-test against `expected` at `level`,
    else why not."""
    mean = r.film.mean_image()
    var = r.film.variance_of_mean_image() + (ROUNDING * expected) ** 2
    if mask is not None:
        mean, var = mean[mask][None], var[mask][None]
    z = mean_z(mean, var, expected)
    p = 2.0 * stats.norm.sf(abs(z))
    if p < level:
        return f"{what}: mean {mean[..., 1].mean():.5f}, expected {expected}, z = {z:.2f}"
    return None


def assert_none_failed(failures):
    failed = [f for f in failures if f]
    assert not failed, "\n".join(failed)


@pytest.fixture(scope="module")
def material_grid(tmp_path_factory):
    grid, scene = furnace_grid(tmp_path_factory.mktemp("grid"), "mesh",
                               [("analytic_sphere", m) for m in GRID_MATERIALS], GRID_COLUMNS, "material_grid")
    return grid, Renderer(scene)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_every_white_glass_is_invisible_in_the_furnace(material_grid, integrator):
    grid, r = material_grid
    render(r, integrator)
    assert_none_failed(furnace_failure(r, 1.0, f"{m} with {integrator}", grid.mask(i))
                       for i, m in enumerate(GRID_MATERIALS)
                       if integrator != "nee" or m not in DELTA_MATERIALS)


def test_white_glass_is_invisible_in_the_furnace_through_packets(tmp_path):
    """The packet path (renderer/packets/: glass lanes through the scalar BSDF one lane at a time)
    keeps the light as the scalar path does: every solid glass of the grid (thin walls have no
    packet form), 4 rays a packet, mis. Its decisions are a family of their own (Sidak over them
    at ALPHA), apart from the module's count."""
    from renderer.packets.program import PacketProgram
    from renderer.renderer import MeshOptions

    solids = [m for m in GRID_MATERIALS if m not in THIN]
    grid, scene = furnace_grid(tmp_path, "mesh", [("analytic_sphere", m) for m in solids], GRID_COLUMNS,
                               "packet_grid")
    r = Renderer(scene, mesh_options=MeshOptions(packets=4))
    assert isinstance(r.program("mis", r.features()), PacketProgram)
    render(r, "mis")
    level = sidak_alpha(ALPHA, len(solids))
    assert_none_failed(furnace_failure(r, 1.0, f"{m} through packets", grid.mask(i), level)
                       for i, m in enumerate(solids))


def test_smooth_glass_under_nee_in_a_furnace_of_its_own(tmp_path):
    grid, scene = furnace_grid(tmp_path, "mesh", [("analytic_sphere", m) for m in DELTA_MATERIALS],
                               len(DELTA_MATERIALS), "delta_grid")
    r = render(Renderer(scene), "nee")
    assert_none_failed(furnace_failure(r, 1.0, f"{m} with nee", grid.mask(i)) for i, m in enumerate(DELTA_MATERIALS))


def test_thin_walls_keep_the_light_inside_too(material_grid):
    grid, r = material_grid
    failures = []
    for material in THIN:
        render(r, "mis", inside_camera(grid.centre(GRID_MATERIALS.index(material))))
        failures.append(furnace_failure(r, 1.0, f"{material}, camera inside"))
    assert_none_failed(failures)


@pytest.mark.parametrize("geometry,shapes", [("mesh", MESH_SHAPES), ("sdf", SDF_SHAPES)], ids=["mesh", "sdf"])
def test_every_shape_keeps_the_light_from_both_sides(tmp_path, geometry, shapes):
    grid, scene = furnace_grid(tmp_path, geometry, [(s, "rough0.3") for s in shapes], len(shapes), f"{geometry}_shapes")
    r = render(Renderer(scene), "mis")
    failures = [furnace_failure(r, 1.0, f"{s}, camera outside", grid.mask(i)) for i, s in enumerate(shapes)]
    for i, shape in enumerate(shapes):
        if shape in CLOSED:
            render(r, "mis", inside_camera(grid.centre(i)))
            failures.append(furnace_failure(r, IOR * IOR, f"{shape}, camera inside"))
    assert_none_failed(failures)


def sppm_failure(material, per_seed, bias=0.0, power=True):
    """None if the mean of `per_seed` (one image mean per independent seed) lies within `bias` of 1
    up to the t-test's margin at LEVEL (bias 0: a plain t-test) and, with `power`, its standard
    error is small enough for a mean SPPM_LOSS below 1 to fail with probability SPPM_POWER; else
    why not."""
    per_seed = np.asarray(per_seed, np.float64)
    n = per_seed.size
    mean, sd = per_seed.mean(), per_seed.std(ddof=1)
    se = sd / np.sqrt(n)
    critical = stats.t.isf(LEVEL / 2, n - 1)
    what = f"sppm {material}: mean {mean:.5f} over {n} seeds (se {se:.5f}, sd {sd:.5f})"
    if abs(mean - 1.0) > bias + critical * se:
        within = f" within {bias:.1%}" if bias else ""
        return f"{what}, expected 1{within}: t = {(mean - 1.0) / se:.2f} (critical {critical:.2f})"
    # a mean SPPM_LOSS low fails with probability SPPM_POWER when SPPM_LOSS - bias >= (critical + z) se
    needed = (SPPM_LOSS - bias) / (critical + stats.norm.isf(1.0 - SPPM_POWER))
    if power and se > needed:
        return f"{what}: too noisy to see a {SPPM_LOSS:.0%} loss with power {SPPM_POWER} (needs se <= {needed:.5f})"
    return None


def sppm_means(r, grid, materials, seeds, iterations, mask_radius=MASK_RADIUS):
    """Per material, the green mean over its cell's mask in each seed's render."""
    masks = [grid.mask(i, mask_radius) for i in range(len(materials))]
    means = [[] for _ in materials]
    for seed in range(1, seeds + 1):
        render(r, "sppm", spp=iterations, seed=seed)
        image = r.image()[..., 1]
        for mask, per_seed in zip(masks, means):
            per_seed.append(image[mask].mean())
    return means


def test_sppm_keeps_the_light(tmp_path):
    """The grid: smooth and rough 0.3 glass, traced through by the camera pass, beside thin rough
    glass, whose visible points take photons (through the others too); thin rough glass's own
    1 % decision is the next test's."""
    grid, scene = furnace_grid(tmp_path, "mesh", [("analytic_sphere", m) for m in SPPM_MATERIALS],
                               len(SPPM_MATERIALS), "sppm_grid")
    r = Renderer(scene)  # one renderer for every seed: its programs compile once
    means = sppm_means(r, grid, SPPM_MATERIALS, SPPM_GRID_SEEDS, SPPM_GRID_ITERATIONS)
    assert_none_failed(sppm_failure(m, per_seed, power=m != "thin-rough") for m, per_seed in zip(SPPM_MATERIALS, means))


def test_sppm_keeps_the_light_of_thin_rough_glass(tmp_path):
    from renderer.integrators.sppm import SppmOptions

    grid, scene = furnace_grid(tmp_path, "mesh", [("analytic_sphere", "thin-rough")], 1, "sppm_thin")
    r = Renderer(scene)
    r.integrator_options["sppm"] = SppmOptions(photons=SPPM_PHOTONS * grid.width * grid.height)
    (per_seed,) = sppm_means(r, grid, ["thin-rough"], SPPM_ALONE_SEEDS, SPPM_ALONE_ITERATIONS, SPPM_MASK_RADIUS)
    assert_none_failed([sppm_failure("thin-rough", per_seed, bias=SPPM_BIAS)])

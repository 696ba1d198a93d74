"""Bezier surfaces of revolution: Newton hits agree with a dense tessellation of the same surface
(random, silhouette and grazing rays) and with closed forms (cylinder, cone); no reported hit is
off the surface or behind the first one; spawned rays do not find their own point; shading data
follows the derivatives; scenes without Bezier surfaces compile none of their code; the goblet
scene loads and renders."""
import math

import numpy as np
import pytest

from renderer.geometry import bezier as bz
from renderer.geometry.mesh_data import MeshData
from renderer.scene.description import Transform
from tests.geometry.mesh_helpers import RayShooter, geometry_from
from tests.geometry.mesh_helpers import SurfaceProbe as Probe  # shared with the hit-point tests

# A vase: flat bottom from the axis (a pole), a convex belly, a concave neck and a flared lip. It
# has every local shape a profile can have: convex, saddle, an inflection and a point on the axis.
VASE = [(0.0, 0.0), (0.5, 0.0), (0.6, 0.1), (0.6, 0.3), (0.6, 0.6), (0.1, 0.7), (0.25, 1.0)]


def placement():
    """Rotated, non-uniformly scaled and moved: the object frame is exercised too."""
    m = np.eye(4)
    m[:3, :3] = Transform(rotate=(20.0, 30.0, -10.0)).rotation_matrix() @ np.diag([1.2, 0.8, 1.0])
    m[:3, 3] = (0.1, -0.2, 0.3)
    return m


class World:
    """One Bezier object, its Newton geometry and a dense tessellation of it (the reference)."""

    def __init__(self, profile, matrix, degree=3, u_steps=96, sectors=384):
        self.cubics = bz.cubic_segments(profile, degree)
        self.matrix = matrix
        self.data = MeshData(**bz.bezier_fields([(self.cubics, matrix, 0, 4, 16)]))
        self.probe = Probe(geometry_from(self.data))
        tris = bz.tessellate(self.cubics, matrix, u_steps, sectors)
        normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        # (triangles at the pole have no area and no normal: they are never hit)
        self.tri_normals = normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)
        self.reference = RayShooter(geometry_from(MeshData(tri_vertices=tris.astype(np.float32),
                                                           tri_material=np.zeros(len(tris), np.int32))))
        self.size = float(np.abs(tris).max())
        # How far the tessellation strays from the surface: each triangle against the surface
        # points at the same parameters, at its edge midpoints and centre (where a chord of a
        # smooth surface strays most, to second order); twice the largest gap bounds it with margin.
        deviation = 0.0
        for c in range(len(self.cubics)):
            def at(i, j):  # world points at fractional grid indices
                uu = np.asarray(i, float)[:, None] / u_steps
                ff = np.asarray(j, float)[None, :] * 2 * np.pi / sectors
                return self.world(np.full((len(uu), ff.shape[1]), c), uu, ff)[0]

            i, j = np.arange(u_steps + 1.0), np.arange(sectors + 1.0)
            w = at(i, j)
            a, b, cc, dd = w[:-1, :-1], w[1:, :-1], w[1:, 1:], w[:-1, 1:]
            i0, j0 = i[:-1], j[:-1]
            pairs = [((a + b) / 2, at(i0 + 0.5, j0)), ((a + dd) / 2, at(i0, j0 + 0.5)),
                     ((a + cc) / 2, at(i0 + 0.5, j0 + 0.5)), ((a + b + cc) / 3, at(i0 + 2 / 3, j0 + 1 / 3)),
                     ((a + cc + dd) / 3, at(i0 + 1 / 3, j0 + 2 / 3))]
            for chord, exact in pairs:
                deviation = max(deviation, float(np.linalg.norm(chord - exact, axis=-1).max()))
        self.tess_error = 2.0 * deviation

    def world(self, curve, u, phi):
        """World point and unit outward normal at (curve, u, phi) (float64)."""
        ctrl = self.cubics[curve]
        S, _, _ = bz.surface_point(ctrl, u, phi)
        _, dc = bz.curve_point(ctrl, u)
        dr, dh = np.broadcast_arrays(dc[..., 0], dc[..., 1], np.asarray(phi))[:2]
        # (S_u x S_phi) / r: defined on the axis too; normals map with the inverse transpose.
        n_obj = np.stack([dh * np.cos(phi), -dr, dh * np.sin(phi)], axis=-1)
        m3 = self.matrix[:3, :3]
        n = n_obj @ np.linalg.inv(m3)
        return S @ m3.T + self.matrix[:3, 3], n / np.linalg.norm(n, axis=-1, keepdims=True)

    def hit_points(self, out):
        """World points S(u, phi) at the reported hits (rows with hit == 1)."""
        rows = out[:, 0] == 1
        prim = out[rows, 2].astype(int)
        curve = self.data.bezier_patch_curve[prim]
        return self.world(curve, out[rows, 3].astype(np.float64), out[rows, 4].astype(np.float64))

    def reference_hits(self, o, d, shift):
        """Tessellation hits of the rays, the cosine of incidence there (0 on a miss), and whether
        the tessellation decides hit or miss: only where the rays moved by `shift` across them
        (4 ways) agree (it strays from the surface by at most tess_error, so a ray whose answer
        survives a move of several times that is not one the tessellation's error could flip)."""
        t, prim = self.reference.closest(o, d)
        cosine = np.where(prim >= 0, np.abs((self.tri_normals[np.maximum(prim, 0)] * d).sum(axis=1)), 0.0)
        a = np.cross(d, [0.0, 0.0, 1.0])
        a = np.where(np.linalg.norm(a, axis=1, keepdims=True) < 1e-3, np.cross(d, [1.0, 0.0, 0.0]), a)
        a /= np.linalg.norm(a, axis=1, keepdims=True)
        b = np.cross(d, a)
        hits = [prim >= 0]
        for offset in (a, -a, b, -b):
            hits.append(self.reference.closest(o + shift * offset, d)[1] >= 0)
        hits = np.array(hits)
        return t, cosine, prim >= 0, hits.all(axis=0) | ~hits.any(axis=0)


@pytest.fixture(scope="module")
def vase():
    return World(VASE, placement())


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def check_on_surface(world, o, d, out, tol=1e-5):
    """Every reported hit lies on the surface where it says: |S(u, phi) - (o + t d)| small."""
    rows = out[:, 0] == 1
    p, _ = world.hit_points(out)
    along = o[rows] + out[rows, 1:2] * d[rows]
    err = np.linalg.norm(p - along, axis=1)
    assert err.max() <= tol * world.size, f"a hit is {err.max():.2e} off the surface"
    # the shading point is that same surface point
    assert np.abs(out[rows, 5:8] - p).max() <= 1e-5 * world.size


def test_tessellation_reference_is_fine_enough(vase):
    # The tolerance every comparison below uses, in units of the object's size.
    assert vase.tess_error < 2e-3 * vase.size


def test_random_rays_agree_with_the_tessellation(vase):
    rng = np.random.default_rng(11)
    n = 4000
    lo, hi = vase.data.scene_bounds()
    o = rng.uniform(lo - 1.0, hi + 1.0, (n, 3))
    d = unit(rng.uniform(lo, hi, (n, 3)) - o)
    out = vase.probe.shoot(o, d)
    hit = out[:, 0] == 1
    t_ref, cosine, hit_ref, decided = vase.reference_hits(o, d, 3.0 * vase.tess_error)
    assert 0.3 < hit.mean() < 0.9
    assert decided.mean() > 0.99, "almost every random ray is far from a silhouette"
    assert np.array_equal(hit[decided], hit_ref[decided]), "hit or miss differs where the tessellation is sure"
    check_on_surface(vase, o, d, out)
    assert check_first_hits(vase, out, t_ref, cosine, hit_ref, both_ways=True) > 0.9 * hit.sum()


def check_first_hits(world, out, t_ref, cosine, hit_ref, min_cosine=0.05, both_ways=False):
    """Where the tessellation crosses its first triangle clearly (cosine of incidence at least
    min_cosine), Newton's first hit is not behind it: t at most the tessellation's error over that
    cosine later. (At a shallower crossing the tessellation's own first hit is ill-posed: along a
    ray that touches the surface the two stay within its error over a long stretch.) Newton may be
    earlier: a ray can dip through the true surface where the tessellation, on the other side of
    it by up to its error, is not crossed; `both_ways` asks for agreement in both directions
    (random rays, which rarely come close to tangency)."""
    clear = (out[:, 0] == 1) & hit_ref & (cosine >= min_cosine)
    tol = 3.0 * world.tess_error / cosine[clear]
    late = out[clear, 1] - t_ref[clear]
    if both_ways:
        late = np.abs(late)
    assert (late <= tol).all(), f"{(late > tol).sum()} hits are not the first the tessellation sees"
    return clear.sum()


def surface_samples(world, rng, n):
    curve = rng.integers(0, len(world.cubics), n)
    u = rng.uniform(0.02, 0.98, n)
    phi = rng.uniform(0.0, 2 * np.pi, n)
    p, normal = world.world(curve, u, phi)
    return p, normal


def test_silhouette_rays(vase):
    """Rays tangent to the surface at a point, moved off it along the normal by multiples of the
    tessellation's error: outward they must miss there, inward hit, as the tessellation says
    wherever it is sure; tangent rays themselves may go either way but never hit wrongly."""
    rng = np.random.default_rng(12)
    n = 1500
    p, normal = surface_samples(vase, rng, n)
    tangent = unit(np.cross(normal, rng.normal(size=(n, 3))))
    moves = np.array([-20.0, -6.0, 0.0, 6.0, 20.0]) * vase.tess_error
    o = (p[None] - 2.0 * tangent[None] + moves[:, None, None] * normal[None]).reshape(-1, 3)
    d = np.broadcast_to(tangent, (len(moves), n, 3)).reshape(-1, 3)
    out = vase.probe.shoot(o, d)
    hit = out[:, 0] == 1
    t_ref, cosine, hit_ref, decided = vase.reference_hits(o, d, 3.0 * vase.tess_error)
    check_on_surface(vase, o, d, out)
    assert np.array_equal(hit[decided], hit_ref[decided]), (
        f"{(hit[decided] != hit_ref[decided]).sum()} of {decided.sum()} decided silhouette rays disagree")
    assert decided.mean() > 0.8  # most moved rays are decided: the test has teeth
    assert check_first_hits(vase, out, t_ref, cosine, hit_ref) > 0.3 * len(o)


@pytest.mark.parametrize("degrees", [0.5, 2.0, 10.0])
def test_grazing_rays_find_the_first_hit(vase, degrees):
    """Rays aimed at a surface point from outside at a grazing angle: each hits, at that point or
    before it (something in front), never after it and never off the surface."""
    rng = np.random.default_rng(13)
    n = 4000
    p, normal = surface_samples(vase, rng, n)
    a = math.radians(degrees)
    d = unit(math.cos(a) * unit(np.cross(normal, rng.normal(size=(n, 3)))) - math.sin(a) * normal)
    o = p - 2.0 * d
    out = vase.probe.shoot(o, d)
    assert (out[:, 0] == 1).all(), "a ray aimed at the surface missed it"
    check_on_surface(vase, o, d, out)
    # Newton's tolerance (1e-6 of the size) along a ray at angle a: at most 1e-6 / sin(a) in t.
    late = out[:, 1] > 2.0 + 1e-5 * vase.size / math.sin(a)
    assert not late.any(), f"{late.sum()} rays went through the surface to a later hit"
    t_ref, cosine, hit_ref, decided = vase.reference_hits(o, d, 3.0 * vase.tess_error)
    check_first_hits(vase, out, t_ref, cosine, hit_ref)


def exact_cone(o, d, r0, r1):
    """First t > 0 of rays on the frustum x^2 + z^2 = (r0 + (r1 - r0) y)^2, 0 <= y <= 1 (float64)."""
    k = r1 - r0
    # (ox + t dx)^2 + (oz + t dz)^2 - (r0 + k (oy + t dy))^2 = 0
    ra = r0 + k * o[:, 1]
    a = d[:, 0] ** 2 + d[:, 2] ** 2 - (k * d[:, 1]) ** 2
    b = 2 * (o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2] - ra * k * d[:, 1])
    c = o[:, 0] ** 2 + o[:, 2] ** 2 - ra ** 2
    disc = b * b - 4 * a * c
    t = np.full(len(o), np.inf)
    sq = np.sqrt(np.maximum(disc, 0.0))
    for sign in (-1.0, 1.0):
        with np.errstate(divide="ignore", invalid="ignore"):
            root = (-b + sign * sq) / (2 * a)
        y = o[:, 1] + root * d[:, 1]
        ok = (disc >= 0) & (root > 1e-9) & (y >= 0) & (y <= 1) & (ra + k * root * d[:, 1] >= 0) & (root < t)
        t = np.where(ok, root, t)
    return t


@pytest.mark.parametrize("r0, r1", [(0.5, 0.5), (0.2, 0.7)], ids=["cylinder", "cone"])
def test_straight_profiles_match_closed_forms(r0, r1):
    """A degree-1 profile is a cylinder or a cone: exact answers to compare with, no tessellation.
    Hit or miss agrees except for rays within 1e-5 of touching an edge or the side tangentially,
    and t to 1e-5 (relative)."""
    cubics = bz.cubic_segments([(r0, 0.0), (r1, 1.0)], 1)
    data = MeshData(**bz.bezier_fields([(cubics, np.eye(4), 0, 2, 12)]))
    probe = Probe(geometry_from(data))
    rng = np.random.default_rng(14)
    n = 6000
    o = rng.uniform(-2, 2, (n, 3)) + [0.0, 0.5, 0.0]
    d = unit(rng.uniform([-0.8, 0.0, -0.8], [0.8, 1.0, 0.8], (n, 3)) - o)
    out = probe.shoot(o, d)
    t = exact_cone(o, d, r0, r1)
    hit = out[:, 0] == 1
    # A ray is undecided when nudging it by 1e-5 across changes the exact answer.
    a = unit(np.cross(d, rng.normal(size=(n, 3))))
    nudged = [np.isfinite(exact_cone(o + s * a, d, r0, r1)) for s in (-1e-5, 1e-5)]
    decided = (nudged[0] == nudged[1]) & (nudged[0] == np.isfinite(t))
    assert decided.mean() > 0.99
    assert np.array_equal(hit[decided], np.isfinite(t)[decided])
    both = hit & np.isfinite(t)
    assert np.abs(out[both, 1] - t[both]).max() <= 1e-5 * np.maximum(1.0, t[both]).max()


def rays_at_surface_points(world, rng, n):
    """(o, d): n rays from random points 3 units away, each aimed at a random point of the surface."""
    p, _ = surface_samples(world, rng, n)
    o = p + unit(rng.normal(size=(n, 3))) * 3.0
    return o, unit(p - o)


def test_spawned_rays_do_not_find_their_own_point(vase):
    rng = np.random.default_rng(15)
    n = 6000
    o, d = rays_at_surface_points(vase, rng, n)
    shooter = RayShooter(vase.probe.geometry)
    first, second, t = shooter.respawn(o, d, unit(rng.normal(size=(n, 3))))
    assert (first >= 0).all()
    again = second >= 0
    # A legitimate second hit on a curved surface lies at least a chord away; a self-hit would
    # be at the spawn offset (~1e-5 of the size).
    assert (t[again] > 1e-3 * vase.size).all(), f"closest second hit at {t[again].min():.2e}"


def test_shading_follows_the_derivatives(vase):
    rng = np.random.default_rng(16)
    n = 3000
    o, d = rays_at_surface_points(vase, rng, n)
    out = vase.probe.shoot(o, d)
    rows = out[:, 0] == 1
    _, n_exact = vase.hit_points(out)
    n_geo = out[rows, 8:11]
    assert np.allclose(np.linalg.norm(n_geo, axis=1), 1.0, atol=1e-5)
    assert (np.abs((n_geo * n_exact).sum(axis=1)) > 1.0 - 1e-5).all()
    assert (n_geo * n_exact).sum(axis=1).min() > 0.0, "normals point out (the profile's orientation)"
    front = out[rows, 17] == 1
    assert np.array_equal(front, (n_geo * d[rows]).sum(axis=1) < 0.0)
    uv = out[rows, 11:13]
    assert (uv >= -1e-4).all() and (uv <= 1.0 + 1e-4).all()
    # u runs along the profile: one equal share of [0, 1] per segment
    curve = vase.data.bezier_patch_curve[out[rows, 2].astype(int)]
    assert np.allclose(uv[:, 0], (curve + out[rows, 3]) / len(vase.cubics), atol=1e-5)
    assert np.allclose(uv[:, 1], out[rows, 4] / (2 * np.pi), atol=1e-5)
    tangent = out[rows, 13:17]
    assert np.allclose(np.linalg.norm(tangent[:, :3], axis=1), 1.0, atol=1e-4)
    assert np.abs((tangent[:, :3] * n_geo).sum(axis=1)).max() < 1e-4
    assert (tangent[:, 3] == 1.0).all()


def test_pole_has_the_axis_as_normal(vase):
    """The bottom meets the axis: there S_phi vanishes; the normal is still the (downward) axis."""
    m = vase.matrix
    axis = unit(np.linalg.inv(m[:3, :3]).T @ np.array([0.0, -1.0, 0.0]))
    bottom = m[:3, 3]
    o = (bottom + 1.5 * axis)[None].repeat(5, axis=0) + np.array([[0, 0, 0], [1e-4, 0, 0], [0, 1e-4, 0],
                                                                   [0, 0, 1e-4], [-1e-4, 1e-4, 0]])
    out = vase.probe.shoot(o, unit(bottom - o))
    assert (out[:, 0] == 1).all()
    assert np.isfinite(out[:, 8:11]).all()
    assert (out[:, 8:11] @ axis > 1.0 - 1e-4).all()


@pytest.mark.filterwarnings("ignore:.*non-taichi function")  # the trap is plain Python on purpose
def test_scene_without_bezier_compiles_no_bezier_code(monkeypatch):
    """The Bezier leaf test sits behind ti.static of the kind: replacing it by a trap shows it is
    compiled into a Bezier scene's traversal and not into any other."""
    from renderer.geometry import bezier_newton

    def trap(*args):
        raise RuntimeError("Bezier code compiled")

    monkeypatch.setattr(bezier_newton, "patch_hit", trap)
    spheres = MeshData(spheres=np.array([[0.0, 0.0, 0.0, 1.0]], np.float32), sphere_material=np.zeros(1, np.int32))
    plain = geometry_from(spheres)
    assert "bezier" not in plain.kinds and not hasattr(plain, "bezier")
    out = Probe(plain).shoot(np.array([[0.0, 0.0, 5.0]]), np.array([[0.0, 0.0, -1.0]]))
    assert out[0, 0] == 1
    both = MeshData(spheres=spheres.spheres, sphere_material=spheres.sphere_material,
                    **bz.bezier_fields([(bz.cubic_segments(VASE, 3), np.eye(4), 0, 1, 4)]))
    with pytest.raises(Exception, match="Bezier code compiled"):
        Probe(geometry_from(both)).shoot(np.array([[0.0, 0.0, 5.0]]), np.array([[0.0, 0.0, -1.0]]))


def test_patch_boxes_hold_their_patches():
    """The BVH finds a patch only through its box: every patch must lie inside it."""
    cubics = bz.cubic_segments(VASE, 3)
    table = bz.patch_table(cubics, 3, 7)
    rng = np.random.default_rng(17)
    for k in range(len(table["curve"])):
        u0, u1, f0, f1 = table["range"][k]
        u = rng.uniform(u0, u1, 200)
        phi = rng.uniform(f0, f1, 200)
        S, _, _ = bz.surface_point(cubics[table["curve"][k]], u, phi)
        lo, hi = table["box"][k]
        assert (S >= lo).all() and (S <= hi).all(), k


def test_profile_helpers():
    # degree elevation keeps the curve
    quad = np.array([[0.0, 0.0], [1.0, 2.0], [2.0, 0.0]])
    cubic = bz.cubic_segments(quad, 2)[0]
    u = np.linspace(0, 1, 11)
    expected = ((1 - u) ** 2)[:, None] * quad[0] + (2 * u * (1 - u))[:, None] * quad[1] + (u ** 2)[:, None] * quad[2]
    assert np.allclose(bz.curve_point(cubic[None], u[:, None])[0].reshape(-1, 2), expected)
    # a sub-curve is the same curve re-parameterised
    part = bz.sub_curve(cubic, 0.25, 0.75)
    assert np.allclose(bz.curve_point(part[None], u[:, None])[0].reshape(-1, 2),
                       bz.curve_point(cubic[None], (0.25 + 0.5 * u)[:, None])[0].reshape(-1, 2))
    # spans turn by at most 30 degrees (a half circle needs at least 6)
    half_circle = bz.cubic_segments([(0, -1), (1.33, -1), (1.33, 1), (0, 1)], 3)[0]
    spans = bz.spans_of(half_circle, 1)
    assert len(spans) >= 6 and spans[0][0] == 0.0 and spans[-1][1] == 1.0
    assert all(bz.tangent_spread(bz.sub_curve(half_circle, a, b)) <= bz.MAX_TURN for a, b in spans)


@pytest.mark.parametrize("points, degree, message", [
    ([(1.0, 0.0)], 3, "profile needs at least 2 points, got 1"),
    ([(0, 0), (1, 0), (1, 1), (1, 2), (0, 3)], 3, "profile has 5 points; a degree-3 profile needs 3k + 1 points (4, 7, 10, ...)"),
    ([(0, 0), (-0.1, 1)], 1, "profile[1] has a negative radius -0.1 (radii must be >= 0)"),
    ([(0, 0), (1, 1), (1, 1), (1, 1), (1, 1)], 2, "profile segment 1 (points 2 to 4) is a single point"),
    ([(0, 0), (0, 1)], 1, "profile segment 0 lies on the axis"),
    ([(0, 0), (1, 1)], 4, "degree 4 is not supported (1 to 3)"),
])
def test_profile_problems(points, degree, message):
    assert message in bz.profile_problem(points, degree)


# --- the goblet scene ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def goblet():
    from renderer.scene.catalog import resolve_scene
    from renderer.scene.toml_loader import load_scene

    return load_scene(resolve_scene("goblet"))


def test_goblet_scene_loads(goblet):
    from renderer.mesh_world import prepare_mesh_scene

    kinds = [o.kind for o in goblet.mesh_objects]
    assert kinds.count("bezier") == 2 and "disc" in kinds
    mesh = prepare_mesh_scene(goblet)
    assert mesh.data.counts["bezier"] > 100
    assert {"dielectric", "conductor", "diffuse"} <= mesh.material_uses()["kinds"]
    # The goblet is a closed solid: its profile starts where the disc under its foot ends.
    glass, foot = goblet.mesh_objects[0], goblet.mesh_objects[1]
    assert glass.profile[0] == (foot.radius, 0.0) and glass.translate == foot.translate
    assert glass.profile[-1][0] == 0.0  # and ends on the axis


@pytest.mark.parametrize("integrator", ["path", "mis"])
def test_goblet_renders_finite(goblet, integrator):
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    r = Renderer(goblet, (32, 32))
    r.render(CameraFrame.from_spec(goblet.camera), 4, integrator=integrator)
    image = r.image()
    assert np.isfinite(image).all() and image.mean() > 0.0
    assert r.film.rejected_counts().sum() == 0, "non-finite samples"

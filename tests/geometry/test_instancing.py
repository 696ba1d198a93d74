"""Instancing: a mesh stored once and placed by matrices traces exactly like the same placements
flattened into world triangles (renderer/scene/mesh_model.py's InstancedMesh.placed is the
reference), with mirrored and non-uniformly scaled instances, through both traversals; the
two-level BVH keeps one copy of the triangles; scenes without instances compile none of it."""
import numpy as np
import pytest
import taichi as ti
import trimesh

from renderer.geometry.instance_bvh import INSTANCE_NODE, build_scene_bvh
from renderer.geometry.interface import INF, Ray
from renderer.geometry.mesh_data import MeshData
from renderer.scene.mesh_model import InstancedMesh, TriangleMesh
from tests.geometry.hit_bounds import U, triangle_shape, triangle_tolerance
from tests.geometry.mesh_helpers import RayShooter, geometry_from

CORNER_ARRAYS = {"tri_vertices": "positions", "tri_normals": "normals", "tri_uvs": "uv0", "tri_uvs1": "uv1",
                 "tri_tangents": "tangents", "tri_colors": "colors"}


def attributed_mesh(rng, positions, faces) -> TriangleMesh:
    """A mesh with every per-vertex attribute: tilted unit normals (so that shading and geometric
    normals differ), two UV sets, tangents orthogonal to the normals with both handednesses, and
    RGBA colours."""
    v = len(positions)
    normals = np.asarray(trimesh.Trimesh(positions, faces, process=False).vertex_normals) + rng.normal(0, 0.2, (v, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    t = rng.normal(size=(v, 3))
    t -= normals * np.einsum("ij,ij->i", normals, t)[:, None]
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    tangents = np.concatenate([t, rng.choice([-1.0, 1.0], (v, 1))], axis=1)
    f32 = lambda a: np.asarray(a, np.float32)
    return TriangleMesh(positions=f32(positions), indices=np.asarray(faces, np.int32), normals=f32(normals),
                        uv0=f32(rng.uniform(0, 1, (v, 2))), uv1=f32(rng.uniform(-1, 2, (v, 2))),
                        tangents=f32(tangents), colors=f32(rng.uniform(0, 1, (v, 4))))


def placements(rng, n, spread=6.0) -> np.ndarray:
    """(n, 4, 4): random rotations, non-uniform scales from 0.3 to 2, every third one mirrored."""
    out = np.tile(np.eye(4), (n, 1, 1))
    for k in range(n):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        scale = rng.uniform(0.3, 2.0, 3) * (-1.0 if k % 3 == 0 else 1.0) ** np.array([1, 0, 0])
        out[k, :3, :3] = q @ np.diag(scale) @ np.linalg.qr(rng.normal(size=(3, 3)))[0]
        out[k, :3, 3] = rng.uniform(-spread, spread, 3)
    return out


def corners(meshes, key):
    """Per-corner arrays of a list of TriangleMeshes, concatenated."""
    return np.concatenate([getattr(m, CORNER_ARRAYS[key])[m.indices] for m in meshes]).astype(np.float32)


def paired_scenes(rng, subdivisions=2, instances=24, loose=40):
    """(instanced MeshData, the same scene flattened, triangles of the world part, of the mesh):
    `loose` random world triangles and `instances` placements of an icosphere."""
    ball = trimesh.creation.icosphere(subdivisions=subdivisions)
    mesh = attributed_mesh(rng, np.asarray(ball.vertices), np.asarray(ball.faces))
    centres = rng.uniform(-6, 6, (loose, 1, 3))
    corners_xyz = (centres + rng.normal(0, 0.6, (loose, 3, 3))).reshape(-1, 3)
    world = [attributed_mesh(rng, corners_xyz, np.arange(len(corners_xyz)).reshape(-1, 3))] if loose else []
    inst = InstancedMesh(mesh, placements(rng, instances))
    flat_meshes = world + [inst.placed(k) for k in range(instances)]
    tw, tm = loose, mesh.triangle_count
    instanced = MeshData(**{key: corners(world + [mesh], key) for key in CORNER_ARRAYS},
                         tri_material=np.zeros(tw + tm, np.int32),
                         instanced_meshes=np.array([[tw, tm]], np.int32),
                         instance_mesh=np.zeros(instances, np.int32), instance_to_world=inst.matrices[:, :3])
    flat = MeshData(**{key: corners(flat_meshes, key) for key in CORNER_ARRAYS},
                    tri_material=np.zeros(tw + instances * tm, np.int32))
    return instanced, flat, tw, tm


def random_rays(rng, n, spread=9.0, target=6.0):
    o = rng.uniform(-spread, spread, (n, 3))
    d = rng.uniform(-target, target, (n, 3)) - o
    return o, d / np.linalg.norm(d, axis=1, keepdims=True)


@ti.data_oriented
class HitProbe:
    """Per ray: hit, t, surface().prim, instance, front_face, then surface() p, n_geo, n_shading,
    uv, uv1, tangent, color and the hit's barycentrics (columns below)."""

    HIT, T, PRIM, INSTANCE, FRONT = 0, 1, 2, 3, 4
    P, N_GEO, N_SHADING, UV, UV1, TANGENT, COLOR, BARY = (slice(5, 8), slice(8, 11), slice(11, 14), slice(14, 16),
                                                          slice(16, 18), slice(18, 22), slice(22, 26), slice(26, 28))
    WIDTH = 28

    def __init__(self, geometry):
        self.geometry = geometry

    @ti.kernel
    def _shoot(self, o: ti.types.ndarray(), d: ti.types.ndarray(), out: ti.types.ndarray()):
        for i in range(o.shape[0]):
            ray = Ray(o=ti.math.vec3(o[i, 0], o[i, 1], o[i, 2]), d=ti.math.vec3(d[i, 0], d[i, 1], d[i, 2]),
                      cone_width=0.0, cone_spread=0.0)
            h = self.geometry.intersect(ray, INF)
            out[i, 0] = h.hit
            if h.hit == 1:
                s = self.geometry.surface(ray, h)
                out[i, 1] = h.t
                out[i, 2] = s.prim
                out[i, 3] = h.instance
                out[i, 4] = s.front_face
                values = [s.p, s.n_geo, s.n_shading, s.uv, s.uv1, s.tangent, s.color, h.bary]
                column = 5
                for v in ti.static(values):
                    for k in ti.static(range(v.n)):
                        out[i, column + k] = v[k]
                    column += v.n

    def shoot(self, o, d):
        out = np.zeros((len(o), self.WIDTH), np.float32)
        self._shoot(np.ascontiguousarray(o, np.float32), np.ascontiguousarray(d, np.float32), out)
        return out


@pytest.fixture(scope="module")
def paired():
    rng = np.random.default_rng(7)
    instanced, flat, tw, tm = paired_scenes(rng)
    return instanced, flat, tw, tm, random_rays(rng, 20000)


def gamma(n):
    return n * U / (1.0 - n * U)


def point_bound(o, d, t, world_tri, instance, instanced: MeshData, object_tri):
    """How far apart (float64, per hit) the hit points of the same ray may lie in the flattened
    and the instanced scene: the f32 triangle test's bound (hit_bounds.triangle_tolerance) in
    the world, plus, for an instance, the same bound in its frame, the rounding of the ray taken
    into that frame (gamma_3 per transformed coordinate; a ray shifted by e crosses a plane at
    most e / cos away) and of the corners taken back (gamma_3), both carried into the world by
    the matrix's largest stretch, and the rounding of the flattened corners to f32."""
    longest, kappa, normal = triangle_shape(world_tri)
    bound = triangle_tolerance(t, longest, kappa, np.abs((d * normal).sum(axis=1)))
    bound += U * np.abs(world_tri).max(axis=(1, 2))
    inst = instance >= 0
    k = instance[inst]
    m = instanced.instance_to_world[k]
    w = np.linalg.inv(m[:, :, :3])
    stretch = np.linalg.norm(m[:, :, :3], ord=2, axis=(1, 2))
    d_obj = np.einsum("nij,nj->ni", w, d[inst])
    speed = np.linalg.norm(d_obj, axis=1)
    o_len, obj_kappa, obj_normal = triangle_shape(object_tri[inst])
    cos_obj = np.abs((d_obj * obj_normal).sum(axis=1)) / speed
    w_norm = np.linalg.norm(w, ord=2, axis=(1, 2))
    ray_error = gamma(3) * (w_norm * (np.linalg.norm(o[inst], axis=1) + t[inst])
                            + np.linalg.norm(np.einsum("nij,nj->ni", w, m[:, :, 3]), axis=1))
    corner = np.abs(object_tri[inst]).max(axis=(1, 2))
    bound[inst] += stretch * (triangle_tolerance(t[inst] * speed, o_len, obj_kappa, cos_obj) + ray_error / cos_obj)
    bound[inst] += gamma(3) * (stretch * corner + np.linalg.norm(m[:, :, 3], axis=1))
    return bound


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_instanced_traversal_equals_flattened(paired, traversal):
    instanced, flat, tw, tm, (o, d) = paired
    got = HitProbe(geometry_from(instanced, traversal=traversal)).shoot(o, d)
    ref = HitProbe(geometry_from(flat, traversal=traversal)).shoot(o, d)
    hit = ref[:, HitProbe.HIT] == 1
    assert hit.sum() > 5000 and (got[hit, HitProbe.INSTANCE] >= 0).sum() > 2000, "rays must hit both kinds"
    np.testing.assert_array_equal(got[:, HitProbe.HIT], ref[:, HitProbe.HIT])
    # The flattened id of instance k's triangle j is tw + k * tm + j; world triangles keep theirs.
    prim, instance = got[hit, HitProbe.PRIM].astype(int), got[hit, HitProbe.INSTANCE].astype(int)
    assert np.array_equal(instance >= 0, prim >= tw)
    ref_prim = ref[hit, HitProbe.PRIM].astype(int)
    o, d, a, b = o[hit], d[hit], got[hit], ref[hit]
    t = b[:, HitProbe.T].astype(np.float64)
    bound = point_bound(o, d, t, flat.tri_vertices[ref_prim], instance, instanced, instanced.tri_vertices[prim])
    assert (np.abs(a[:, HitProbe.T] - t) <= bound).all()
    same = np.where(instance >= 0, tw + instance * tm + (prim - tw), prim) == ref_prim
    # Two triangles hit within the bound of each other (at a shared edge): either is right.
    assert same.mean() > 0.999
    a, b, bound, g = a[same], b[same], bound[same], ref_prim[same]
    np.testing.assert_array_equal(a[:, HitProbe.FRONT], b[:, HitProbe.FRONT])
    assert (np.linalg.norm(a[:, HitProbe.P] - b[:, HitProbe.P], axis=1) <= bound).all()
    longest, kappa, normal = triangle_shape(flat.tri_vertices[g])
    # Barycentrics move by at most bound / (smallest altitude >= longest / kappa) each.
    bary = bound * kappa / longest
    for column, key in ((HitProbe.UV, "tri_uvs"), (HitProbe.UV1, "tri_uvs1"), (HitProbe.COLOR, "tri_colors")):
        spread = spread_of(getattr(flat, key)[g].astype(np.float64))
        assert (np.abs(a[:, column] - b[:, column]).max(axis=1) <= 2 * bary * spread + 4 * U).all(), key
    # Normals: the geometric one from corners moved by at most gamma_3-rounding (<= bound), the
    # shading one from normals interpolated at moved barycentrics and transformed in f32.
    geometric = 4 * bound * kappa / longest + 8 * U
    assert (np.linalg.norm(a[:, HitProbe.N_GEO] - b[:, HitProbe.N_GEO], axis=1) <= geometric).all()
    weights = np.concatenate([1.0 - b[:, HitProbe.BARY].sum(axis=1, keepdims=True), b[:, HitProbe.BARY]], axis=1)
    stretch = np.array([np.linalg.cond(instanced.instance_to_world[k, :, :3]) if k >= 0 else 0.0
                        for k in a[:, HitProbe.INSTANCE].astype(int)])
    normals = flat.tri_normals[g].astype(np.float64)
    interp = np.linalg.norm(np.einsum("ni,nij->nj", weights, normals), axis=1)
    shading = (2 * bary * spread_of(normals) + gamma(8) * (1 + stretch)) / interp
    assert (np.linalg.norm(a[:, HitProbe.N_SHADING] - b[:, HitProbe.N_SHADING], axis=1) <= shading).all()
    # Tangents: interpolated the same way, then made orthogonal to the shading normal.
    tangents = flat.tri_tangents[g].astype(np.float64)
    tg = np.einsum("ni,nij->nj", weights, tangents[:, :, :3])
    ns = b[:, HitProbe.N_SHADING].astype(np.float64)
    across = np.linalg.norm(tg - ns * (ns * tg).sum(axis=1, keepdims=True), axis=1)
    tangent = (2 * bary * spread_of(tangents[:, :, :3]) + 2 * shading * np.linalg.norm(tg, axis=1)
               + gamma(8) * (1 + stretch)) / across
    diff = a[:, HitProbe.TANGENT] - b[:, HitProbe.TANGENT]
    assert (np.linalg.norm(diff[:, :3], axis=1) <= tangent).all()
    np.testing.assert_array_equal(a[:, HitProbe.TANGENT][:, 3], b[:, HitProbe.TANGENT][:, 3])


def spread_of(corner_vectors):
    """Largest distance between two corners' values, per triangle (N, 3, k)."""
    v = corner_vectors
    return np.max([np.linalg.norm(v[:, i] - v[:, j], axis=1) for i, j in ((0, 1), (1, 2), (0, 2))], axis=0)


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_scene_of_instances_alone_equals_flattened(traversal):
    """No world primitives: the instance tree is the whole world part."""
    rng = np.random.default_rng(8)
    instanced, flat, _, tm = paired_scenes(rng, subdivisions=1, instances=40, loose=0)
    o, d = random_rays(rng, 4000)
    got = HitProbe(geometry_from(instanced, traversal=traversal)).shoot(o, d)
    ref = HitProbe(geometry_from(flat, traversal=traversal)).shoot(o, d)
    np.testing.assert_array_equal(got[:, HitProbe.HIT], ref[:, HitProbe.HIT])
    hit = ref[:, HitProbe.HIT] == 1
    prim, instance = got[hit, HitProbe.PRIM].astype(int), got[hit, HitProbe.INSTANCE].astype(int)
    ref_prim = ref[hit, HitProbe.PRIM].astype(int)
    assert hit.sum() > 500 and (instance * tm + prim == ref_prim).mean() > 0.999
    t = ref[hit, HitProbe.T].astype(np.float64)
    bound = point_bound(o[hit], d[hit], t, flat.tri_vertices[ref_prim], instance, instanced,
                        instanced.tri_vertices[prim])
    assert (np.abs(got[hit, HitProbe.T] - t) <= bound).all()


@pytest.mark.parametrize("traversal", ["stack", "stackless"])
def test_instanced_any_hit_equals_flattened(paired, traversal):
    instanced, flat, _, _, (o, d) = paired
    t_ref, _ = RayShooter(geometry_from(flat, traversal=traversal)).closest(o, d)
    shooter = RayShooter(geometry_from(instanced, traversal=traversal))
    for t_max in (2.0, 8.0, INF):
        blocked = shooter.occluded(o, d, t_max) == 1
        clear = np.abs(t_ref - t_max) > 1e-4 * np.maximum(1.0, t_ref)  # not at the very end of the segment
        assert np.array_equal(blocked[clear], (t_ref < t_max)[clear])
        assert blocked.sum() > 1000


def test_world_part_and_mesh_trees_are_laid_out_as_documented(paired):
    """Every instance appears once in the instance tree, each box holds what it bounds, the mesh
    tree's leaves hold exactly the mesh's triangles, and skip links leave a part at its end."""
    instanced, _, tw, tm, _ = paired
    bvh = build_scene_bvh(instanced)
    nodes = bvh.nodes
    is_instance = nodes.node_count == INSTANCE_NODE
    assert sorted(nodes.node_a[is_instance]) == list(range(len(instanced.instance_mesh)))
    lo, hi = instanced.instance_bounds()
    first, count = instanced.instanced_meshes[0]
    local = instanced.tri_vertices[first:first + count].reshape(-1, 3).astype(np.float64)
    for node in np.flatnonzero(is_instance):
        k = nodes.node_a[node]
        m = instanced.instance_to_world[k]
        world = local @ m[:, :3].T + m[:, 3]
        assert (world >= nodes.node_lo[node]).all() and (world <= nodes.node_hi[node]).all()
        assert np.allclose(nodes.node_lo[node], lo[k], atol=1e-5)
    root = bvh.mesh_root[0]
    assert root > np.flatnonzero(is_instance).max()  # mesh trees come after the world part
    leaves = (nodes.node_count > 0) & (np.arange(nodes.num_nodes) >= root)
    slots = np.concatenate([nodes.prim_order[a:a + c] for a, c in zip(nodes.node_a[leaves], nodes.node_count[leaves])])
    assert sorted(slots) == list(range(tw, tw + tm))
    assert (nodes.node_skip[root:] <= nodes.num_nodes).all() and nodes.node_skip[root] == nodes.num_nodes


def test_memory_holds_one_copy_of_the_mesh():
    """1,000 instances of a 20,480-triangle icosphere: the triangles, their attributes and their
    tree are stored once; each instance adds its 100-byte record and about two instance-tree
    nodes (36 bytes each)."""
    rng = np.random.default_rng(3)
    ball = trimesh.creation.icosphere(subdivisions=5)
    tris = np.asarray(ball.vertices, np.float32)[np.asarray(ball.faces)]
    n, m = len(tris), 1000
    once = MeshData(tri_vertices=tris, tri_material=np.zeros(n, np.int32))
    many = MeshData(tri_vertices=tris, tri_material=np.zeros(n, np.int32),
                    instanced_meshes=np.array([[0, n]], np.int32), instance_mesh=np.zeros(m, np.int32),
                    instance_to_world=placements(rng, m, spread=100.0)[:, :3])
    single, instanced = geometry_from(once).device_bytes(), geometry_from(many).device_bytes()
    assert instanced["triangles"] == single["triangles"] == 36 * n
    assert instanced["instances"] == 100 * m
    per_instance = (instanced["total"] - single["total"]) / m
    assert 100 < per_instance <= 100 + 2 * 36 + 4, per_instance
    # And the instances are there: rays towards instance centres hit them.
    centres = many.instance_to_world[:, :, 3]
    o = centres + np.array([0.0, 0.0, 300.0])
    _, prim = RayShooter(geometry_from(many)).closest(o, np.tile([0.0, 0.0, -1.0], (m, 1)))
    assert (prim >= 0).all()


@pytest.mark.filterwarnings("ignore:.*non-taichi function")  # the trap is plain Python on purpose
def test_scene_without_instances_compiles_no_instance_code(monkeypatch):
    """The frame changes sit behind ti.static(has_instances): a trap in their place shows they
    compile into an instanced scene's traversal and not into others."""
    from renderer.geometry.instances import InstanceTable

    def trap(*args):
        raise RuntimeError("instance code compiled")

    monkeypatch.setattr(InstanceTable, "ray_to_object", trap)
    rng = np.random.default_rng(5)
    instanced, flat, _, _ = paired_scenes(rng, subdivisions=1, instances=3)
    o, d = random_rays(rng, 64)
    plain = geometry_from(flat)
    assert not plain.has_instances and not hasattr(plain, "instances")
    assert RayShooter(plain).closest(o, d)[1].max() >= 0
    with pytest.raises(Exception, match="instance code compiled"):
        RayShooter(geometry_from(instanced)).closest(o, d)

"""Lambert lanes with shading normals (renderer/packets/lambert.py, shading_normals.py) against the
scalar code they stand in for: the consistent shading normal, the lobe's value and density toward
a direction and the validity of its samples (Bsdf.eval_at, pbrt's rule for directions the shading
normal and the surface disagree on), and a triangle's interpolated vertex normal
(MeshGeometry.surface). Deterministic comparisons over fixed-seed random configurations."""
import numpy as np
import pytest
import taichi as ti
import trimesh

from renderer.geometry.interface import Hit, Ray, Surface
from renderer.geometry.mesh_data import MeshData
from renderer.geometry.shading import consistent_shading_normal
from renderer.packets import lambert
from renderer.packets.shading_normals import consistent_normals, interpolated_normals
from renderer.scene.description import MaterialSpec
from renderer.scene.features import Features
from tests.geometry.mesh_helpers import geometry_from
from tests.materials.bsdf_kernels import FixedBench

W = 4
vec3 = ti.math.vec3
ALBEDO = (0.7, 0.5, 0.3)


@ti.kernel
def _lane_lambert(ng: ti.types.ndarray(dtype=vec3, ndim=1), s: ti.types.ndarray(dtype=vec3, ndim=1),
                  wo: ti.types.ndarray(dtype=vec3, ndim=1), wi: ti.types.ndarray(dtype=vec3, ndim=1),
                  u: ti.types.ndarray(dtype=ti.math.vec2, ndim=1), out: ti.types.ndarray(ndim=2)):
    for p in range(ng.shape[0] // W):
        z = ti.Vector([0.0] * W)
        nx, ny, nz, sx, sy, sz, ox, oy, oz, ix, iy, iz, v1, v2 = z, z, z, z, z, z, z, z, z, z, z, z, z, z
        for k in ti.static(range(W)):
            i = p * W + k
            nx[k], ny[k], nz[k] = ng[i].x, ng[i].y, ng[i].z
            sx[k], sy[k], sz[k] = s[i].x, s[i].y, s[i].z
            ox[k], oy[k], oz[k] = wo[i].x, wo[i].y, wo[i].z
            ix[k], iy[k], iz[k] = wi[i].x, wi[i].y, wi[i].z
            v1[k], v2[k] = u[i].x, u[i].y
        snx, sny, snz = consistent_normals(sx, sy, sz, nx, ny, nz, ox, oy, oz)
        fx, fy, fz = lambert.lobe_normal(snx, sny, snz, ox * nx + oy * ny + oz * nz)
        cos_i, pdf, usable = lambert.toward(ix, iy, iz, fx, fy, fz, snx, sny, snz, nx, ny, nz, ox, oy, oz)
        bx, by, bz, b_pdf, valid = lambert.sample(v1, v2, fx, fy, fz, snx, sny, snz, nx, ny, nz, ox, oy, oz)
        for k in ti.static(range(W)):
            i = p * W + k
            out[i, 0], out[i, 1], out[i, 2] = snx[k], sny[k], snz[k]
            out[i, 3], out[i, 4], out[i, 5] = cos_i[k], pdf[k], ti.cast(usable[k], ti.f32)
            out[i, 6], out[i, 7], out[i, 8] = bx[k], by[k], bz[k]
            out[i, 9], out[i, 10] = b_pdf[k], ti.cast(valid[k], ti.f32)


@ti.kernel
def _scalar_lambert(bsdf: ti.template(), material: ti.i32, ng: ti.types.ndarray(dtype=vec3, ndim=1),
                    s: ti.types.ndarray(dtype=vec3, ndim=1), wo: ti.types.ndarray(dtype=vec3, ndim=1),
                    wi: ti.types.ndarray(dtype=vec3, ndim=1), sampled: ti.types.ndarray(dtype=vec3, ndim=1),
                    out: ti.types.ndarray(ndim=2)):
    for i in range(ng.shape[0]):
        ns = consistent_shading_normal(s[i], ng[i], wo[i])
        surface = Surface(p=vec3(0.0), n_geo=ng[i], n_shading=ns, uv=ti.math.vec2(0.0), uv1=ti.math.vec2(0.0),
                          tangent=ti.math.vec4(0.0), material=material, prim=0, front_face=1, eps=0.0,
                          cone_width=0.0, cone_spread=0.0)
        mat, n = bsdf.shade(surface, wo[i])
        value, pdf = bsdf.eval_at(mat, n, ng[i], wo[i], wi[i])
        b_value, b_pdf = bsdf.eval_at(mat, n, ng[i], wo[i], sampled[i])
        out[i, 0], out[i, 1], out[i, 2] = ns.x, ns.y, ns.z
        out[i, 3], out[i, 4], out[i, 5] = value.x, value.y, value.z
        out[i, 6] = pdf
        out[i, 7], out[i, 8] = b_value.x, b_pdf


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def configurations(count: int, seed: int):
    """Geometric normals; raw shading normals tilted from them by up to 85 degrees (a tenth turned
    below the surface, which consistency turns back); viewer directions from the whole sphere (a
    tenth within 0.3 degrees of grazing, where consistency bends the normal); light directions from
    the whole sphere; sample numbers."""
    rng = np.random.default_rng(seed)
    ng = unit(rng.normal(size=(count, 3)))
    away = unit(np.cross(ng, rng.normal(size=(count, 3))))
    tilt = rng.uniform(0.0, np.radians(85.0), count)[:, None]
    s = np.cos(tilt) * ng + np.sin(tilt) * away
    s[: count // 10] *= -1.0
    wo = unit(rng.normal(size=(count, 3)))
    graze = slice(count // 10, count // 5)
    in_plane = unit(wo[graze] - np.einsum("ij,ij->i", wo[graze], ng[graze])[:, None] * ng[graze])
    lift = rng.uniform(-0.005, 0.005, (len(in_plane), 1))
    wo[graze] = unit(in_plane + lift * ng[graze])
    wi = unit(rng.normal(size=(count, 3)))
    u = rng.random((count, 2))
    return [a.astype(np.float32) for a in (ng, s, wo, wi, u)]


def test_lambert_lanes_shade_as_the_scalar_bsdf_does():
    count = 8192
    ng, s, wo, wi, u = configurations(count, seed=3)
    lanes = np.zeros((count, 11), np.float32)
    _lane_lambert(ng, s, wo, wi, u, lanes)
    bench = FixedBench([MaterialSpec(name="white", kind="diffuse", base_color=ALBEDO)],
                       Features(material_kinds=frozenset({"diffuse"})))
    material = next(iter(bench.ids.values()))
    scalar = np.zeros((count, 9), np.float32)
    _scalar_lambert(bench.bsdf, material, ng, s, wo, wi, np.ascontiguousarray(lanes[:, 6:9]), scalar)

    # the consistent shading normal, bent ones included
    np.testing.assert_allclose(lanes[:, 0:3], scalar[:, 0:3], atol=2e-6)
    grazing = slice(count // 10, count // 5)
    assert np.mean(np.abs(np.einsum("ij,ij->i", s[grazing], lanes[grazing, 0:3])) < 0.999) > 0.1  # bent

    # toward a direction: the value (albedo cos / pi) where usable, nothing elsewhere; the density
    cos_i, pdf, usable = lanes[:, 3], lanes[:, 4], lanes[:, 5] == 1
    clear = np.abs(cos_i) > 1e-5  # away from the lobe's horizon, where rounding may decide either way
    value = scalar[:, 3:6]
    np.testing.assert_allclose(value[usable], np.outer(cos_i[usable] / np.pi, ALBEDO), rtol=1e-4, atol=1e-7)
    assert (value[~usable & clear] == 0.0).all()
    assert ((value[clear].max(axis=1) > 0.0) == usable[clear]).all()
    np.testing.assert_allclose(pdf[usable], scalar[usable, 6], rtol=1e-4, atol=1e-7)
    # the sides rule is exercised: lit from the lobe's side, yet below the true surface
    below = (cos_i > 1e-3) & (np.einsum("ij,ij->i", wi, ng) * np.einsum("ij,ij->i", wo, ng) < -1e-3)
    assert below.sum() > 100 and not usable[below].any()

    # samples: valid exactly where the scalar BSDF sees the sampled direction lit, at its density
    valid, b_pdf = lanes[:, 10] == 1, lanes[:, 9]
    sampled = lanes[:, 6:9]
    geometric = np.abs(np.einsum("ij,ij->i", sampled, ng)) > 1e-5
    firm = geometric & (b_pdf > 1e-5)
    assert ((scalar[firm, 7] > 0.0) == valid[firm]).all()
    assert 0.05 < np.mean(~valid) < 0.5  # some samples fall below the true surface and end the path
    np.testing.assert_allclose(b_pdf[valid], scalar[valid, 8], rtol=1e-4, atol=1e-7)


@ti.kernel
def _interpolated(geometry: ti.template(), prim: ti.types.ndarray(dtype=ti.i32, ndim=1),
                  bary: ti.types.ndarray(dtype=ti.math.vec2, ndim=1), wo: ti.types.ndarray(dtype=vec3, ndim=1),
                  out: ti.types.ndarray(ndim=2)):
    for p in range(prim.shape[0] // W):
        z = ti.Vector([0.0] * W)
        g = ti.Vector([0] * W)
        b1, b2, nx, ny, nz, ox, oy, oz = z, z, z, z, z, z, z, z
        for k in ti.static(range(W)):
            i = p * W + k
            g[k] = prim[i]
            b1[k], b2[k] = bary[i].x, bary[i].y
            ox[k], oy[k], oz[k] = wo[i].x, wo[i].y, wo[i].z
            v0, v1, v2 = geometry.corners_of(ti.max(prim[i], 0))
            n = ti.math.normalize((v1 - v0).cross(v2 - v0))
            nx[k], ny[k], nz[k] = n.x, n.y, n.z
        sx, sy, sz = interpolated_normals(geometry, g, b1, b2, nx, ny, nz)
        sx, sy, sz = consistent_normals(sx, sy, sz, nx, ny, nz, ox, oy, oz)
        for k in ti.static(range(W)):
            i = p * W + k
            out[i, 0], out[i, 1], out[i, 2] = sx[k], sy[k], sz[k]
            if prim[i] >= 0:
                surface = geometry.surface(Ray(o=vec3(0.0), d=-wo[i], cone_width=0.0, cone_spread=0.0),
                                           Hit(hit=1, t=1.0, prim=prim[i], bary=bary[i], instance=-1))
                out[i, 3], out[i, 4], out[i, 5] = surface.n_shading.x, surface.n_shading.y, surface.n_shading.z
            else:  # no hit: the geometric normal, made consistent all the same
                n = consistent_shading_normal(vec3(nx[k], ny[k], nz[k]), vec3(nx[k], ny[k], nz[k]), wo[i])
                out[i, 3], out[i, 4], out[i, 5] = n.x, n.y, n.z


@pytest.mark.parametrize("zero_corners", [False, True])
def test_interpolated_normals_are_the_surface_records(zero_corners):
    """A coarse icosphere's vertex normals at random points of random triangles (and lanes with no
    hit, which keep the geometric normal), seen from the whole sphere: the lanes' consistent
    shading normal is MeshGeometry.surface's. With every third triangle's corner normals zero (a
    mesh part without normals) those fall back to the geometric normal in both."""
    ball = trimesh.creation.icosphere(subdivisions=1, radius=0.5)
    tris = ball.vertices[ball.faces].astype(np.float32)
    normals = ball.vertex_normals[ball.faces].astype(np.float32)
    if zero_corners:
        normals[::3] = 0.0
    data = MeshData(tri_vertices=tris, tri_normals=normals, tri_material=np.zeros(len(tris), np.int32))
    geometry = geometry_from(data, traversal="wide4")
    assert geometry.has_normals
    rng = np.random.default_rng(5)
    count = 4096
    prim = rng.integers(0, len(tris), count).astype(np.int32)
    prim[::17] = -1
    b = rng.random((count, 2))
    b = np.where(b.sum(axis=1, keepdims=True) > 1.0, 1.0 - b, b).astype(np.float32)
    wo = unit(rng.normal(size=(count, 3))).astype(np.float32)
    out = np.zeros((count, 6), np.float32)
    _interpolated(geometry, prim, b, wo, out)
    np.testing.assert_allclose(out[:, 0:3], out[:, 3:6], atol=2e-6)
    # the vertex normals were used: they lean away from the faces' own
    faces = unit(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]))[np.maximum(prim, 0)]
    lean = np.abs(np.einsum("ij,ij->i", out[:, 0:3], faces)) < 0.9999
    assert lean.mean() > (0.4 if zero_corners else 0.6)

"""Rough conductors as lanes (renderer/packets/conductor.py) against the scalar BSDF they stand in
for, without energy compensation (as in pbrt's and Mitsuba's scenes) and with it: the value and density toward a
direction (Bsdf.eval_at, shading normals and pbrt's sides rule included), each sample's weight and
density (the scalar f cos / pdf and pdf at the sampled direction) and validity, and the samples'
distribution (chi-square against the scalar density, level 0.01 with Sidak's correction)."""
import numpy as np
import pytest
import taichi as ti

from renderer.geometry.interface import Surface
from renderer.geometry.shading import consistent_shading_normal
from renderer.materials.table import alpha_of
from renderer.packets import conductor
from renderer.packets.lambert import lobe_normal
from renderer.packets.shading_normals import consistent_normals
from renderer.scene.description import MaterialSpec
from renderer.scene.features import Features
from tests.materials.bsdf_kernels import FixedBench, chi2_adaptive
from tests.packets.test_packet_lambert import configurations, unit

W = 4
vec3 = ti.math.vec3
# Rows the lanes take: a measured metal (eta, k), an artist's metal (base colour, edge tint,
# specular tint), and a nearly smooth one (veach-mis's plates go down to alpha 1e-4)
SPECS = (MaterialSpec(name="copper", kind="conductor", roughness=0.45, eta=(0.2, 0.92, 1.1), k=(3.9, 2.45, 2.14)),
         MaterialSpec(name="gold", kind="conductor", roughness=0.3, base_color=(1.0, 0.78, 0.34),
                      edge_tint=(0.9, 0.9, 0.6), specular_color=(0.9, 1.0, 1.0)),
         MaterialSpec(name="polished", kind="conductor", roughness=0.1, eta=(0.2, 0.92, 1.1), k=(3.9, 2.45, 2.14)))


@pytest.fixture(scope="module", params=[False, True], ids=["single", "compensated"])
def bench(request):
    bench = FixedBench(SPECS, Features(material_kinds=frozenset({"conductor"}), energy_compensation=request.param))
    assert (bench.bsdf.energy is not None) == request.param
    return bench


@ti.kernel
def _lanes(table: ti.template(), energy: ti.template(), material: ti.types.ndarray(dtype=ti.i32, ndim=1),
           ng: ti.types.ndarray(dtype=vec3, ndim=1), s: ti.types.ndarray(dtype=vec3, ndim=1),
           wo: ti.types.ndarray(dtype=vec3, ndim=1), wi: ti.types.ndarray(dtype=vec3, ndim=1),
           u: ti.types.ndarray(dtype=vec3, ndim=1), out: ti.types.ndarray(ndim=2)):
    for p in range(ng.shape[0] // W):
        z = ti.Vector([0.0] * W)
        m = ti.Vector([0] * W)
        nx, ny, nz, sx, sy, sz, ox, oy, oz, ix, iy, iz, lobe, v1, v2 = z, z, z, z, z, z, z, z, z, z, z, z, z, z, z
        for k in ti.static(range(W)):
            i = p * W + k
            m[k] = material[i]
            nx[k], ny[k], nz[k] = ng[i].x, ng[i].y, ng[i].z
            sx[k], sy[k], sz[k] = s[i].x, s[i].y, s[i].z
            ox[k], oy[k], oz[k] = wo[i].x, wo[i].y, wo[i].z
            ix[k], iy[k], iz[k] = wi[i].x, wi[i].y, wi[i].z
            lobe[k], v1[k], v2[k] = u[i].x, u[i].y, u[i].z
        snx, sny, snz = consistent_normals(sx, sy, sz, nx, ny, nz, ox, oy, oz)
        fx, fy, fz = lobe_normal(snx, sny, snz, ox * nx + oy * ny + oz * nz)
        alpha = z * 0.0
        for k in ti.static(range(W)):
            alpha[k] = alpha_of(table[m[k]].roughness)
        vr, vg, vb, pdf = conductor.toward(table, energy, m, alpha, ix, iy, iz, fx, fy, fz, snx, sny, snz, nx, ny, nz,
                                           ox, oy, oz)
        bx, by, bz, wr, wg, wb, b_pdf, valid = conductor.sample(table, energy, m, alpha, lobe, v1, v2, fx, fy, fz, snx,
                                                                sny, snz, nx, ny, nz, ox, oy, oz)
        for k in ti.static(range(W)):
            i = p * W + k
            out[i, 0], out[i, 1], out[i, 2], out[i, 3] = vr[k], vg[k], vb[k], pdf[k]
            out[i, 4], out[i, 5], out[i, 6] = bx[k], by[k], bz[k]
            out[i, 7], out[i, 8], out[i, 9] = wr[k], wg[k], wb[k]
            out[i, 10], out[i, 11] = b_pdf[k], ti.cast(valid[k], ti.f32)


@ti.kernel
def _scalar(bsdf: ti.template(), material: ti.types.ndarray(dtype=ti.i32, ndim=1),
            ng: ti.types.ndarray(dtype=vec3, ndim=1), s: ti.types.ndarray(dtype=vec3, ndim=1),
            wo: ti.types.ndarray(dtype=vec3, ndim=1), wi: ti.types.ndarray(dtype=vec3, ndim=1),
            sampled: ti.types.ndarray(dtype=vec3, ndim=1), out: ti.types.ndarray(ndim=2)):
    for i in range(ng.shape[0]):
        ns = consistent_shading_normal(s[i], ng[i], wo[i])
        surface = Surface(p=vec3(0.0), n_geo=ng[i], n_shading=ns, uv=ti.math.vec2(0.0), uv1=ti.math.vec2(0.0),
                          tangent=ti.math.vec4(0.0), material=material[i], prim=0, front_face=1, eps=0.0,
                          cone_width=0.0, cone_spread=0.0)
        mat, n = bsdf.shade(surface, wo[i])
        value, pdf = bsdf.eval_at(mat, n, ng[i], wo[i], wi[i])
        b_value, b_pdf = bsdf.eval_at(mat, n, ng[i], wo[i], sampled[i])
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = value.x, value.y, value.z, pdf
        out[i, 4], out[i, 5], out[i, 6], out[i, 7] = b_value.x, b_value.y, b_value.z, b_pdf


def run_lanes(bench, material, ng, s, wo, wi, u):
    out = np.zeros((len(ng), 12), np.float32)
    _lanes(bench.table.table, bench.bsdf.energy, material, ng, s, wo, wi, u, out)
    return out


def test_conductor_lanes_evaluate_and_sample_as_the_scalar_bsdf_does(bench):
    count = 12288
    ng, s, wo, wi, u2 = configurations(count, seed=11)
    u = np.concatenate([np.random.default_rng(13).random((count, 1)), u2], axis=1).astype(np.float32)
    # light directions near the mirror direction about the shading normal as well, where the
    # narrow lobes have their value
    near = slice(count // 2, count)
    mirror = 2.0 * np.einsum("ij,ij->i", wo[near], s[near])[:, None] * s[near] - wo[near]
    wi[near] = unit(mirror + 0.2 * np.random.default_rng(12).normal(size=mirror.shape)).astype(np.float32)
    material = np.array([bench.ids[SPECS[i % 3]] for i in range(count)], np.int32)
    lanes = run_lanes(bench, material, ng, s, wo, wi, u)
    scalar = np.zeros((count, 8), np.float32)
    _scalar(bench.bsdf, material, ng, s, wo, wi, np.ascontiguousarray(lanes[:, 4:7]), scalar)

    # f32 arithmetic in the world frame (lanes) and in the lobe's frame (scalar) round apart: values
    # agree to 1e-3 relative (narrow lobes' peaks, 1 / (pi alpha^2), amplify the half vector's rounding)
    value, pdf = lanes[:, 0:3], lanes[:, 3]
    lit = scalar[:, 0:3].max(axis=1) > 0.0
    assert lit.sum() > count // 4
    np.testing.assert_allclose(value, scalar[:, 0:3], rtol=1e-3, atol=1e-6)
    np.testing.assert_allclose(pdf, scalar[:, 3], rtol=1e-3, atol=1e-6)
    # the sides rule: lit from the lobe's side, yet below the true surface
    below = np.einsum("ij,ij->i", wi, ng) * np.einsum("ij,ij->i", wo, ng) < -1e-3
    assert (below & (pdf > 1e-3)).sum() > 100 and (value[below] == 0.0).all()

    # samples: the weight is f cos / pdf at the sampled direction, its density the scalar one, and
    # valid exactly where the scalar BSDF sees that direction lit (away from horizons)
    valid, b_pdf, weight = lanes[:, 11] == 1, lanes[:, 10], lanes[:, 7:10]
    b_value, scalar_pdf = scalar[:, 4:7], scalar[:, 7]
    sampled = lanes[:, 4:7]
    firm = (np.abs(np.einsum("ij,ij->i", sampled, ng)) > 1e-4) & (b_pdf > 1e-4)
    assert ((b_value[firm].max(axis=1) > 0.0) == valid[firm]).all()
    assert 0.02 < np.mean(~valid) < 0.6
    ok = valid & (scalar_pdf > 1e-6)
    np.testing.assert_allclose(b_pdf[ok], scalar_pdf[ok], rtol=1e-3)
    np.testing.assert_allclose(weight[ok], b_value[ok] / scalar_pdf[ok, None], rtol=2e-3, atol=1e-6)


# Direction space resolves lobes from roughness 0.3 up (tests/materials/test_bsdf_chi2.py tests the
# narrower ones in slope space); the sampler's code is the same for every width, and the narrow
# lobe's samples are checked point by point above.
CASES = [(spec, cos_o) for spec in (0, 1) for cos_o in (0.95, 0.5, 0.12)]


@pytest.mark.parametrize("spec, cos_o", CASES)
def test_conductor_lane_samples_follow_the_scalar_density(bench, spec, cos_o):
    """200,000 lane samples about a plain normal (no shading normal), binned over the sphere,
    against the scalar BSDF's density of sampling (cell probabilities integrated adaptively; the
    density leaves out the samples reflected below the surface: lossy)."""
    count = 200_000
    n = np.array([0.0, 0.0, 1.0])
    wo = np.array([np.sqrt(1.0 - cos_o ** 2), 0.0, cos_o])
    rng = np.random.default_rng(100 + spec * 10 + int(cos_o * 100))
    tile = lambda v: np.tile(v, (count, 1)).astype(np.float32)  # noqa: E731
    material = np.full(count, bench.ids[SPECS[spec]], np.int32)
    lanes = run_lanes(bench, material, tile(n), tile(n), tile(wo), tile(n), rng.random((count, 3)).astype(np.float32))
    result = chi2_adaptive(lanes[:, 4:7].astype(np.float64), bench.pdf_callable(bench.ids[SPECS[spec]], n, wo),
                           valid=lanes[:, 11] == 1, lossy=True, alpha=0.01, num_tests=len(CASES))
    assert result, result.report


@pytest.mark.parametrize("compensation", [False, True])
def test_packets_render_rough_conductors_as_lanes_with_the_scalar_paths_image(tmp_path, compensation):
    """The Cornell box of every material kind (a rough conductor box, a mirror, glass, a principled
    paint), with and without energy compensation: the rough conductor's lanes are shaded as lanes,
    the others through the scalar BSDF; the image is the scalar path's (the suite's z-tests)."""
    from renderer.packets.program import PacketProgram
    from tests.packets.test_packet_render import render
    from tests.packets.test_packet_shading import cornell_of_materials
    from tests.stats.image_tests import assert_agree

    path = cornell_of_materials(tmp_path)
    text = path.read_text()
    assert "[render]\n" in text
    path.write_text(text.replace("[render]\n", f"[render]\nenergy_compensation = {str(compensation).lower()}\n", 1))
    scalar = render(path, 0, "mis", seed=81, spp=256, size=(20, 20))
    packed = render(path, 4, "mis", seed=82, spp=256, size=(20, 20))
    program = packed.program("mis", packed.features(), "independent")
    assert isinstance(program, PacketProgram) and program.lane_conductors
    assert (program.bsdf.energy is not None) == compensation
    assert_agree((packed.image(), packed.film.variance_of_mean_image()),
                 (scalar.image(), scalar.film.variance_of_mean_image()), ("packets", "scalar"))

"""Kernels calling every Taichi func of renderer/media (grid media's lookups and tracking in a second
one, over a small grid) and renderer/spectral, so that a test can run them on another back-end
(Vulkan) and compare with the CPU. Run as a script:
`python -m tests.media.library_kernel ARCH OUT.npy` (initialises Taichi on ARCH)."""
import sys

import numpy as np
import taichi as ti

from renderer.geometry.interface import Ray
from renderer.media import grid
from renderer.media import homogeneous as hm
from renderer.media import phase
from renderer.media.grid_table import GridMedia
from renderer.sampling.rng import SampleState, sample_key
from renderer.scene.description import MediumSpec, VolumeGridSpec
from renderer.spectral import cie, ior, upsample
from renderer.spectral import wavelengths as wl

vec2, vec3, vec4 = ti.math.vec2, ti.math.vec3, ti.math.vec4


@ti.kernel
def library_kernel(out: ti.types.ndarray(dtype=ti.f32, ndim=2)):
    for i in range(out.shape[0]):
        u = (i + 0.5) / out.shape[0]
        wo = ti.math.normalize(vec3(0.3, -0.5, 0.8))
        wi, pdf = phase.hg_sample(0.7, wo, vec2(u, 1.0 - u))
        out[i, 0] = pdf
        out[i, 1] = phase.hg_eval(-0.4, wo.dot(wi)) + phase.hg_phase(0.7, wo, wi)
        s = hm.sample_distance(vec3(0.1, 0.2, 0.3), vec3(0.5), 2.0, u, 1.0 - u)
        out[i, 2] = s.weight.sum() + s.t + s.scattered
        out[i, 3] = (hm.exponential_fog(vec3(1.0), vec3(0.5), 0.3, 2.0 * u) + hm.transmittance(vec3(0.2), u)).sum()
        lams, pdfs = wl.sample_hero_wavelengths(u)
        out[i, 4] = lams.sum() + 100.0 * pdfs.sum()
        out[i, 5] = (cie.spectral_rgb_weights(lams[0]) / pdfs[0] + cie.xyz_to_rec709(cie.cmf_xyz(lams[1]))).sum()
        out[i, 6] = upsample.rgb_to_spectrum4(vec3(0.2, 0.5, 0.9), lams).sum()
        b, c = ti.static(ior.SELLMEIER_PRESETS["water"])
        out[i, 7] = ior.sellmeier_ior(lams[2], vec4(*b), vec4(*c)) + ior.cauchy_ior(lams[3], 1.5, 0.004)
        out[i, 8] = (wl.sample_uniform_wavelength(u) * wl.uniform_wavelength_pdf(500.0)
                     + wl.visible_wavelength_pdf(wl.sample_visible_wavelength(u)))


@ti.kernel
def grid_kernel(grids: ti.template(), out: ti.types.ndarray(dtype=ti.f32, ndim=2)):
    for i in range(out.shape[0]):
        u = (i + 0.5) / out.shape[0]
        state = SampleState(pixel=ti.u32(i), index=ti.u32(1), seed=ti.u32(5), key=sample_key(i, 1, 5))
        ray = Ray(o=vec3(-1.0, 0.1 + 0.5 * u, 0.2), d=ti.math.normalize(vec3(1.0, 0.2, 0.3 * u)), cone_width=0.0,
                  cone_spread=0.0)
        out[i, 0] = grid.lookup(grids.volumes, grids.voxels, 0, ray.o + 1.3 * u * ray.d).sum()
        out[i, 1] = grids.transmittance(0, ray, 2.5, grid.tracking_key(state, 7, grid.point_salt(ray.o))).sum()
        s = grids.free_flight(0, ray, 2.0, vec3(1.0, 0.5, 0.25), grid.tracking_key(state, 8, 0))
        out[i, 2] = s.weight.sum() + s.t + s.scattered


def grid_media() -> GridMedia:
    values = np.random.default_rng(4).random((3, 4, 5, 3)).astype(np.float32)
    density = VolumeGridSpec(values, to_world=((1.5, 0.0, 0.0, -0.5), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, -0.2),
                                               (0.0, 0.0, 0.0, 1.0)))
    albedo = VolumeGridSpec(values[..., ::-1].copy(), nearest=True)
    return GridMedia([MediumSpec("smoke", kind="grid", density=density, albedo=albedo, scale=3.0)])


def run() -> np.ndarray:
    out = np.zeros((256, 9), np.float32)
    library_kernel(out)
    grid_out = np.zeros((256, 3), np.float32)
    grid_kernel(grid_media(), grid_out)
    return np.concatenate([out, grid_out], axis=1)


if __name__ == "__main__":
    from renderer.runtime.arch import init_taichi

    init_taichi(sys.argv[1], offline_cache=False)
    np.save(sys.argv[2], run())

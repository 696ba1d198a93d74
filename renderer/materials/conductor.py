"""The `conductor` kind: GGX reflection with a conductor's Fresnel (renderer/materials/lobes.py:
from base_color and edge_tint, or exact from eta + i k); with energy compensation a rough one adds
Kulla and Conty's multiple-scattering lobe (Bsdf.metal_eval). Roughness 0 is a delta mirror.
Lobe module of renderer/materials/kinds.py (see diffuse.py)."""
import taichi as ti

from renderer.materials import lobes
from renderer.materials import microfacet as mf
from renderer.materials.kinds import LobeFlags
from renderer.materials.lobes import BsdfSample
from renderer.materials.microfacet import GGX


@ti.func
def sample(bsdf, mat, n_f, t, b, entering, wo, u1, u2):
    s = lobes.invalid_sample()
    model, alpha_v = mf.row_model(bsdf, mat), mf.row_alpha_v(bsdf, mat)
    if ti.static(not bsdf.compensate):
        s = lobes.conductor_sample(mat, wo, u2, model, alpha_v)
    elif mat.alpha == 0.0 or model != GGX or alpha_v >= 0.0:  # one scattering; the tables are isotropic GGX's
        s = lobes.conductor_sample(mat, wo, u2, model, alpha_v)
    else:
        wi = bsdf.metal_direction(mat.alpha, wo, u1, u2)
        if wi.z > 0.0:
            value, pdf = evaluate(bsdf, mat, n_f, t, b, entering, wo, wi)
            if pdf > 0.0:
                s = BsdfSample(wi=wi, weight=value / pdf, pdf=pdf, delta=0, valid=1)
    return s


@ti.func
def evaluate(bsdf, mat, n_f, t, b, entering, wo, wi):
    h = ti.math.normalize(wo + wi)
    fresnel = lobes.conductor_reflectance(mat, wo.dot(h))
    return bsdf.metal_eval(fresnel, lobes.conductor_reflectance_average(mat), mat.alpha, wo, wi,
                           mf.row_model(bsdf, mat), mf.row_alpha_v(bsdf, mat))


@ti.func
def flags(bsdf, mat):
    return LobeFlags.REFLECTION | (LobeFlags.GLOSSY if mat.alpha > 0.0 else LobeFlags.SPECULAR)

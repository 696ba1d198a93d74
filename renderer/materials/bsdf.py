"""The material table on the device and its BSDF: diffuse, GGX conductor, smooth/rough dielectric.

Which lobes are compiled in is decided by `Features` (`ti.static`), so a scene without glass
carries no refraction code. Roughness 0 is an exact delta lobe, never a tiny GGX.

Frames: `n` is the outward geometric/shading normal, `wo` points back along the incoming ray.
Sampling returns `weight = f * |cos| / pdf`, the factor a path's throughput is multiplied by.
"""
import numpy as np
import taichi as ti

from renderer.materials import microfacet as mf
from renderer.sampling.warps import INV_PI, cosine_hemisphere, orthonormal_basis, to_local, to_world

DIFFUSE, CONDUCTOR, DIELECTRIC = 0, 1, 2
KIND_IDS = {"diffuse": DIFFUSE, "conductor": CONDUCTOR, "dielectric": DIELECTRIC}

# Only roughness == 0 is a delta lobe. Any other roughness is clamped to at least this GGX width so
# that D(h) <= 1/(pi a^2) ~ 3e7 stays finite in f32.
MIN_ALPHA = 1e-4

Material = ti.types.struct(kind=ti.i32, base_color=ti.math.vec3, alpha=ti.f32, ior=ti.f32, emission=ti.math.vec3)
BsdfSample = ti.types.struct(wi=ti.math.vec3, weight=ti.math.vec3, pdf=ti.f32, delta=ti.i32, valid=ti.i32)


def material_arrays(materials) -> dict:
    """Material specs to plain arrays, one row per material (index = material id)."""
    rows = list(materials) or []
    alpha = [0.0 if m.roughness == 0.0 else max(m.roughness ** 2, MIN_ALPHA) for m in rows]
    return {
        "kind": np.array([KIND_IDS[m.kind] for m in rows], np.int32),
        "base_color": np.array([m.base_color for m in rows], np.float32).reshape(-1, 3),
        "alpha": np.array(alpha, np.float32),
        "ior": np.array([m.ior for m in rows], np.float32),
        "emission": np.array([m.emission for m in rows], np.float32).reshape(-1, 3),
    }


@ti.data_oriented
class MaterialTable:
    """All of a scene's materials in one struct field, indexed by material id."""

    def __init__(self, materials):
        arrays = material_arrays(materials)
        self.count = len(arrays["kind"])
        self.table = Material.field(shape=max(1, self.count))
        if self.count:
            self.table.from_numpy(arrays)


@ti.data_oriented
class Bsdf:
    """The BSDF over a material table, with only the lobes `features` calls for compiled in."""

    def __init__(self, materials: MaterialTable, features):
        self.materials = materials
        self.features = features

    @ti.func
    def get(self, mat_id):
        return self.materials.table[mat_id]

    @ti.func
    def sample(self, mat, n, wo_world, u):
        """Sample wi given wo. u is a vec3 of uniforms (lobe choice, 2D direction)."""
        n_f = n if n.dot(wo_world) >= 0.0 else -n  # the side wo is on
        t, b = orthonormal_basis(n_f)
        wo = to_local(wo_world, t, b, n_f)
        s = BsdfSample(wi=ti.math.vec3(0.0, 0.0, 1.0), weight=ti.math.vec3(0.0), pdf=0.0, delta=0, valid=0)
        if wo.z > 0.0:
            if ti.static(self.features.has_diffuse):
                if mat.kind == DIFFUSE:
                    s = _sample_diffuse(mat, wo, u)
            if ti.static(self.features.has_conductor):
                if mat.kind == CONDUCTOR:
                    s = _sample_conductor(mat, wo, u)
            if ti.static(self.features.has_dielectric):
                if mat.kind == DIELECTRIC:
                    entering = n.dot(wo_world) >= 0.0
                    eta = mat.ior if entering else 1.0 / mat.ior
                    s = _sample_dielectric(mat, wo, eta, u)
        s.wi = to_world(s.wi, t, b, n_f)
        return s

    @ti.func
    def eval(self, mat, n, wo_world, wi_world):
        """f * |cos(wi)| and the solid-angle pdf of sampling wi, for the non-delta reflection lobes."""
        n_f = n if n.dot(wo_world) >= 0.0 else -n
        t, b = orthonormal_basis(n_f)
        wo = to_local(wo_world, t, b, n_f)
        wi = to_local(wi_world, t, b, n_f)
        value = ti.math.vec3(0.0)
        pdf = 0.0
        if wo.z > 0.0 and wi.z > 0.0:
            if ti.static(self.features.has_diffuse):
                if mat.kind == DIFFUSE:
                    value = mat.base_color * (wi.z * INV_PI)
                    pdf = wi.z * INV_PI
            if ti.static(self.features.has_conductor):
                if mat.kind == CONDUCTOR and mat.alpha > 0.0:
                    h = ti.math.normalize(wo + wi)
                    f = mf.fresnel_schlick(mat.base_color, wo.dot(h))
                    value = f * mf.ggx_d(h, mat.alpha) * mf.smith_g2(wo, wi, mat.alpha) / (4.0 * wo.z)
                    pdf = mf.visible_normal_pdf(wo, h, mat.alpha) / (4.0 * wo.dot(h))
        return value, pdf

    @ti.func
    def albedo(self, mat):
        """A display albedo for the debug view (not an integral of the BSDF)."""
        return mat.base_color


@ti.func
def _sample_diffuse(mat, wo, u):
    wi = cosine_hemisphere(ti.math.vec2(u.y, u.z))
    return BsdfSample(wi=wi, weight=mat.base_color, pdf=wi.z * INV_PI, delta=0, valid=1)


@ti.func
def _sample_conductor(mat, wo, u):
    s = BsdfSample(wi=ti.math.vec3(-wo.x, -wo.y, wo.z), weight=ti.math.vec3(0.0), pdf=1.0, delta=1, valid=1)
    if mat.alpha == 0.0:
        s.weight = mf.fresnel_schlick(mat.base_color, wo.z)
    else:
        h = mf.sample_visible_normal(wo, mat.alpha, ti.math.vec2(u.y, u.z))
        wi = mf.reflect(wo, h)
        s.delta = 0
        if wi.z > 0.0:
            cos_oh = wo.dot(h)
            s.wi = wi
            # f cos / pdf with pdf = G1 D (wo.h) / (4 wo.z wo.h): D and the Jacobian cancel.
            s.weight = mf.fresnel_schlick(mat.base_color, cos_oh) * (
                mf.smith_g2(wo, wi, mat.alpha) / mf.smith_g1(wo, mat.alpha))
            s.pdf = mf.visible_normal_pdf(wo, h, mat.alpha) / (4.0 * cos_oh)
        else:
            s.valid = 0
    return s


@ti.func
def _sample_dielectric(mat, wo, eta, u):
    """eta = n on the far side / n on wo's side. Lobe choice by Fresnel, so F cancels in the weight.

    Transmission scales radiance by 1/eta^2 (radiance is not conserved across a change of
    index; Veach 1997, 5.2); a round trip in and out of a solid multiplies to 1.
    """
    s = BsdfSample(wi=ti.math.vec3(0.0, 0.0, 1.0), weight=ti.math.vec3(0.0), pdf=0.0, delta=1, valid=1)
    h = ti.math.vec3(0.0, 0.0, 1.0)
    g_ratio = 1.0
    if mat.alpha > 0.0:
        h = mf.sample_visible_normal(wo, mat.alpha, ti.math.vec2(u.y, u.z))
        s.delta = 0
    cos_oh = wo.dot(h)
    f, cos_t = mf.fresnel_dielectric(cos_oh, eta)
    reflect = u.x < f
    if reflect:
        s.wi = mf.reflect(wo, h)
    else:
        s.wi = mf.refract(wo, h, eta, cos_t)
    # A rough microfacet can send wi to the wrong side of the macro surface: no contribution.
    if (reflect and s.wi.z <= 0.0) or ((not reflect) and s.wi.z >= 0.0):
        s.valid = 0
    else:
        if mat.alpha > 0.0:
            g_ratio = mf.smith_g2(wo, ti.math.vec3(s.wi.x, s.wi.y, ti.abs(s.wi.z)), mat.alpha) / mf.smith_g1(wo, mat.alpha)
            d_vis = mf.visible_normal_pdf(wo, h, mat.alpha)
            if reflect:
                s.pdf = f * d_vis / (4.0 * cos_oh)
            else:
                cos_ih = s.wi.dot(h)
                # Walter et al. 2007, eq. 17: d(h)/d(wi) = eta^2 |wi.h| / (wo.h + eta wi.h)^2
                denom = cos_oh + eta * cos_ih
                s.pdf = (1.0 - f) * d_vis * eta * eta * ti.abs(cos_ih) / (denom * denom)
        else:
            s.pdf = f if reflect else 1.0 - f
        if reflect:
            s.weight = ti.math.vec3(g_ratio)
        else:
            s.weight = mat.base_color * (g_ratio / (eta * eta))
    return s

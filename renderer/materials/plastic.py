"""The `plastic` kind: Mitsuba 3's plastic and roughplastic. A diffuse base (base_color) under a
dielectric coating of index `ior`: the coating reflects specularly (a delta mirror when smooth, a
microfacet lobe of the row's model when rough, tinted by specular_color), the base's diffuse light
passes the coating twice with its internal reflections summed in closed form (the numbers and the
formula are renderer/materials/plastic_tables.py's). The lobe is chosen by the coating's
reflectance at wo against its transmittance, weighted by the specular and diffuse albedos, as
Mitsuba chooses. Lobe module of renderer/materials/kinds.py (see diffuse.py)."""
import taichi as ti

from renderer.materials import lobes
from renderer.materials import microfacet as mf
from renderer.materials.kinds import LobeFlags
from renderer.materials.lobes import BsdfSample
from renderer.sampling.warps import INV_PI, cosine_hemisphere

vec3 = ti.math.vec3
TABLE_SIZE = 64  # renderer/materials/plastic_tables.py TABLE_SIZE


@ti.func
def _transmittance(bsdf, mat, table, cos_theta):
    """The coating's transmittance from outside at cos_theta: 1 - F when smooth, else the row's
    table, interpolated linearly between its TABLE_SIZE cosines from 0 to 1."""
    t = 0.0
    if table < 0:
        f, _ = mf.fresnel_dielectric(ti.math.clamp(cos_theta, 0.0, 1.0), mat.ior)
        t = 1.0 - f
    else:
        if ti.static(bsdf.materials.has_plastic_tables):  # a scene with rough plastics
            x = ti.math.clamp(cos_theta, 0.0, 1.0) * (TABLE_SIZE - 1)
            i = ti.min(ti.cast(x, ti.i32), TABLE_SIZE - 2)
            t = ti.math.mix(bsdf.materials.plastic_transmittance[table, i],
                            bsdf.materials.plastic_transmittance[table, i + 1], x - ti.cast(i, ti.f32))
    return t


@ti.func
def _specular_probability(mat, t_o):
    """The chance of sampling the coating at wo: its reflectance (1 - transmittance) against the
    transmittance, weighted by the row's specular share of the albedos."""
    w = mat.specular_weight
    p_spec = (1.0 - t_o) * w
    p_diff = t_o * (1.0 - w)
    return p_spec / ti.max(p_spec + p_diff, 1e-12)


@ti.func
def _diffuse(mat, t_o, t_i, cos_i):
    """The base's light through the coating, f |cos(wi)|."""
    rho = mat.base_color
    k = vec3(mat.internal_reflectance)
    if mat.nonlinear == 1:
        k = rho * mat.internal_reflectance
    return rho / (1.0 - k) * (t_o * t_i * cos_i * INV_PI / (mat.ior * mat.ior))


@ti.func
def _rough_specular(bsdf, mat, wo, wi):
    h = ti.math.normalize(wo + wi)
    f, _ = mf.fresnel_dielectric(ti.math.clamp(wo.dot(h), 0.0, 1.0), mat.ior)
    return lobes.ggx_reflection_eval(mat.specular_color * f, mat.alpha, wo, wi, mf.row_model(bsdf, mat))


@ti.func
def evaluate(bsdf, mat, n_f, t, b, entering, wo, wi):
    value = vec3(0.0)
    pdf = 0.0
    if wi.z > 0.0:
        table = mat.plastic_table
        t_o = _transmittance(bsdf, mat, table, wo.z)
        t_i = _transmittance(bsdf, mat, table, wi.z)
        p_spec = _specular_probability(mat, t_o)
        value = _diffuse(mat, t_o, t_i, wi.z)
        pdf = (1.0 - p_spec) * wi.z * INV_PI
        if mat.alpha > 0.0:
            spec, spec_pdf = _rough_specular(bsdf, mat, wo, wi)
            value += spec
            pdf += p_spec * spec_pdf
    return value, pdf


@ti.func
def sample(bsdf, mat, n_f, t, b, entering, wo, u1, u2):
    s = lobes.invalid_sample()
    table = mat.plastic_table
    t_o = _transmittance(bsdf, mat, table, wo.z)
    p_spec = _specular_probability(mat, t_o)
    if mat.alpha == 0.0 and u1 < p_spec:
        f, _ = mf.fresnel_dielectric(wo.z, mat.ior)
        s = BsdfSample(wi=vec3(-wo.x, -wo.y, wo.z), weight=mat.specular_color * (f / p_spec), pdf=p_spec, delta=1,
                       valid=1)
    else:
        wi = vec3(0.0)
        if u1 < p_spec:
            wi = lobes.ggx_reflection_direction(mat.alpha, wo, u2, mf.row_model(bsdf, mat))
        else:
            wi = cosine_hemisphere(u2)
        if wi.z > 0.0:
            value, pdf = evaluate(bsdf, mat, n_f, t, b, entering, wo, wi)
            if pdf > 0.0:
                s = BsdfSample(wi=wi, weight=value / pdf, pdf=pdf, delta=0, valid=1)
    return s


@ti.func
def flags(bsdf, mat):
    return LobeFlags.REFLECTION | LobeFlags.DIFFUSE | (LobeFlags.GLOSSY if mat.alpha > 0.0 else LobeFlags.SPECULAR)

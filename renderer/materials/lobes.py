"""BSDF lobes in the local shading frame (z = the normal on wo's side, so wo.z > 0).

Each lobe has `eval(...) -> (f * |cos wi|, pdf)` and a sampler returning a `BsdfSample` whose
`weight = f * |cos| / pdf` and `pdf` agree with `eval` for non-delta directions. Delta lobes
(roughness 0) are sampled only; their `pdf` is the discrete probability of the choice.

Dielectric conventions: `eta` = n on the far side / n on wo's side. Transmitted radiance is scaled
by 1 / eta^2 (radiance is not invariant across a change of index; Veach 1997, 5.2), so a path in
and out of a solid multiplies to 1.
"""
import taichi as ti

from renderer.materials import microfacet as mf
from renderer.sampling.warps import INV_PI, cosine_hemisphere

vec3 = ti.math.vec3
BsdfSample = ti.types.struct(wi=vec3, weight=vec3, pdf=ti.f32, delta=ti.i32, valid=ti.i32)


@ti.func
def invalid_sample():
    return BsdfSample(wi=vec3(0.0, 0.0, 1.0), weight=vec3(0.0), pdf=0.0, delta=0, valid=0)


# --- Lambert ---------------------------------------------------------------------------------------
@ti.func
def diffuse_eval(albedo, wo, wi):
    value = vec3(0.0)
    pdf = 0.0
    if wi.z > 0.0:
        value = albedo * (wi.z * INV_PI)
        pdf = wi.z * INV_PI
    return value, pdf


@ti.func
def diffuse_sample(albedo, wo, u2):
    wi = cosine_hemisphere(u2)
    return BsdfSample(wi=wi, weight=albedo, pdf=wi.z * INV_PI, delta=0, valid=1 if wi.z > 0.0 else 0)


# --- Fresnel of conductors ---------------------------------------------------------------------------
# cos(82 degrees) and the normaliser of the F82 correction term: cos (1 - cos)^6 at 82 degrees.
_COS_82 = 0.13917310096
_F82_NORM = 0.13917310096 * (1.0 - 0.13917310096) ** 6


@ti.func
def conductor_fresnel(cos_i, reflectivity, edge_tint):
    """A conductor's Fresnel from its colour at normal incidence and an edge tint: Schlick's curve
    with Hoffman's F82 correction (Hoffman 2019, 'Fresnel equations considered harmful'; as in
    OpenPBR): F = Schlick(F0) - a cos (1 - cos)^6, with `a` chosen so that F(82 degrees) =
    edge_tint * Schlick(F0, 82 degrees). Tint 1 is plain Schlick; below 1 it darkens the
    grazing dip that real metals show. Stable for F0 = 1 (a perfect mirror stays exactly 1)."""
    c = ti.math.clamp(cos_i, 0.0, 1.0)
    schlick_82 = mf.fresnel_schlick(reflectivity, _COS_82)
    a = schlick_82 * (1.0 - ti.math.clamp(edge_tint, 0.0, 1.0)) / _F82_NORM
    m = 1.0 - c
    m2 = m * m
    return ti.math.clamp(mf.fresnel_schlick(reflectivity, c) - a * c * m2 * m2 * m2, 0.0, 1.0)


@ti.func
def schlick_average(f0):
    """Cosine-weighted mean of Schlick's Fresnel, 2 int F(mu) mu dmu = F0 + (1 - F0) / 21."""
    return f0 + (1.0 - f0) / 21.0


@ti.func
def conductor_fresnel_average(reflectivity, edge_tint):
    """Cosine-weighted mean of conductor_fresnel: Schlick's mean minus the F82 term's,
    2 int a mu^2 (1 - mu)^6 dmu = a / 126 (the clamp to [0, 1] is ignored: it acts only where the
    F82 term would drive F below zero)."""
    a = mf.fresnel_schlick(reflectivity, _COS_82) * (1.0 - ti.math.clamp(edge_tint, 0.0, 1.0)) / _F82_NORM
    return ti.math.clamp(schlick_average(reflectivity) - a / 126.0, 0.0, 1.0)


@ti.func
def conductor_reflectance(mat, cos_i):
    """The Fresnel of a conductor material at cos_i, by the row's switch: exact from its complex
    index eta + i k (`complex_ior`), or from base_color and edge_tint (conductor_fresnel); times
    the row's specular_color."""
    f = vec3(0.0)
    if mat.complex_ior == 1:
        f = mf.fresnel_conductor(cos_i, mat.eta, mat.k)
    else:
        f = conductor_fresnel(cos_i, mat.base_color, mat.edge_tint)
    return f * mat.specular_color  # a tint (Mitsuba's specular_reflectance), white unless given


@ti.func
def conductor_reflectance_average(mat):
    """Cosine-weighted mean of conductor_reflectance: stored in the row for a complex index
    (quadrature on the host), in closed form for base_color and edge_tint."""
    f = vec3(0.0)
    if mat.complex_ior == 1:
        f = mat.fresnel_avg
    else:
        f = conductor_fresnel_average(mat.base_color, mat.edge_tint)
    return f * mat.specular_color


# --- GGX reflection (conductor, metal, dielectric coat) ------------------------------------------------
@ti.func
def ggx_reflection_eval(fresnel, alpha, wo, wi, model=mf.GGX, alpha_v=mf.ISOTROPIC):
    """fresnel: the Fresnel factor at wo.h (vec3); the caller computes it for h = normalize(wo + wi).
    model: the microfacet model (microfacet.py; GGX unless a row names another)."""
    value = vec3(0.0)
    pdf = 0.0
    if wi.z > 0.0 and alpha > 0.0:
        h = ti.math.normalize(wo + wi)
        cos_oh = wo.dot(h)
        if cos_oh > 0.0:
            value = fresnel * (mf.d(h, alpha, model, alpha_v) * mf.g2(wo, wi, alpha, model, alpha_v) / (4.0 * wo.z))
            pdf = mf.normal_pdf(wo, h, alpha, model, alpha_v) / (4.0 * cos_oh)
    return value, pdf


@ti.func
def ggx_reflection_direction(alpha, wo, u2, model=mf.GGX, alpha_v=mf.ISOTROPIC):
    return mf.reflect(wo, mf.sample_normal(wo, alpha, u2, model, alpha_v))


@ti.func
def conductor_eval(mat, wo, wi, model=mf.GGX, alpha_v=mf.ISOTROPIC):
    """mat: a conductor Material (its alpha and Fresnel description); model: its microfacet model."""
    h = ti.math.normalize(wo + wi)
    return ggx_reflection_eval(conductor_reflectance(mat, wo.dot(h)), mat.alpha, wo, wi, model, alpha_v)


@ti.func
def conductor_sample(mat, wo, u2, model=mf.GGX, alpha_v=mf.ISOTROPIC):
    s = invalid_sample()
    alpha = mat.alpha
    if alpha == 0.0:
        s = BsdfSample(wi=vec3(-wo.x, -wo.y, wo.z), weight=conductor_reflectance(mat, wo.z), pdf=1.0, delta=1,
                       valid=1)
    else:
        h = mf.sample_normal(wo, alpha, u2, model, alpha_v)
        wi = mf.reflect(wo, h)
        cos_oh = wo.dot(h)
        if wi.z > 0.0 and cos_oh > 0.0:  # (a guard: rounding can leave a sampled normal facing away from wo)
            # f cos / pdf: D and the Jacobian cancel (microfacet.sampled_weight).
            weight = conductor_reflectance(mat, cos_oh) * mf.sampled_weight(wo, wi, h, alpha, model, alpha_v)
            s = BsdfSample(wi=wi, weight=weight, pdf=mf.normal_pdf(wo, h, alpha, model, alpha_v) / (4.0 * cos_oh),
                           delta=0, valid=1)
    return s


# --- Dielectric interface (rough: Walter et al. 2007; smooth: delta) -------------------------------------
@ti.func
def dielectric_eval(tint, alpha, eta, wo, wi, model=mf.GGX, alpha_v=mf.ISOTROPIC):
    value = vec3(0.0)
    pdf = 0.0
    if alpha > 0.0 and wi.z != 0.0:
        if wi.z > 0.0:
            h = ti.math.normalize(wo + wi)
            cos_oh = wo.dot(h)
            if cos_oh > 0.0:
                f, _ = mf.fresnel_dielectric(cos_oh, eta)
                value = vec3(f * mf.d(h, alpha, model, alpha_v) * mf.g2(wo, wi, alpha, model, alpha_v) / (4.0 * wo.z))
                pdf = f * mf.normal_pdf(wo, h, alpha, model, alpha_v) / (4.0 * cos_oh)
        else:
            # Generalised half vector of a refraction, on wo's side.
            h = ti.math.normalize(wo + eta * wi)
            if h.z < 0.0:
                h = -h
            cos_oh = wo.dot(h)
            cos_ih = wi.dot(h)
            if cos_oh > 0.0 and cos_ih < 0.0:
                f, _ = mf.fresnel_dielectric(cos_oh, eta)
                denom = cos_oh + eta * cos_ih
                denom2 = denom * denom
                d = mf.d(h, alpha, model, alpha_v)
                value = tint * ((1.0 - f) * d * mf.g2(wo, wi, alpha, model, alpha_v) * cos_oh * ti.abs(cos_ih)
                                / (wo.z * denom2))
                # Walter et al. 2007, eq. 17: d(h)/d(wi) = eta^2 |wi.h| / (wo.h + eta wi.h)^2
                pdf = (1.0 - f) * mf.normal_pdf(wo, h, alpha, model, alpha_v) * eta * eta * ti.abs(cos_ih) / denom2
    return value, pdf


@ti.func
def dielectric_sample(tint, alpha, eta, wo, u1, u2, model=mf.GGX, alpha_v=mf.ISOTROPIC):
    """Lobe choice by Fresnel, so F cancels in the weight."""
    s = BsdfSample(wi=vec3(0.0, 0.0, 1.0), weight=vec3(0.0), pdf=0.0, delta=1, valid=1)
    h = vec3(0.0, 0.0, 1.0)
    g_ratio = 1.0
    if alpha > 0.0:
        h = mf.sample_normal(wo, alpha, u2, model, alpha_v)
        s.delta = 0
    cos_oh = wo.dot(h)
    facing_away = cos_oh <= 0.0  # (a guard: rounding can leave a sampled normal facing away from wo)
    cos_oh = ti.max(cos_oh, 0.0)
    f, cos_t = mf.fresnel_dielectric(cos_oh, eta)
    reflect = u1 < f
    if reflect:
        s.wi = mf.reflect(wo, h)
    else:
        s.wi = mf.refract(wo, h, eta, cos_t)
    # A rough microfacet can send wi to the wrong side of the macro surface: no contribution.
    if (reflect and s.wi.z <= 0.0) or ((not reflect) and s.wi.z >= 0.0) or facing_away:
        s.valid = 0
    else:
        if alpha > 0.0:
            g_ratio = mf.sampled_weight(wo, s.wi, h, alpha, model, alpha_v)
            d_vis = mf.normal_pdf(wo, h, alpha, model, alpha_v)
            if reflect:
                s.pdf = f * d_vis / (4.0 * cos_oh)
            else:
                cos_ih = s.wi.dot(h)
                denom = cos_oh + eta * cos_ih
                s.pdf = (1.0 - f) * d_vis * eta * eta * ti.abs(cos_ih) / (denom * denom)
        else:
            s.pdf = f if reflect else 1.0 - f
        if reflect:
            s.weight = vec3(g_ratio)
        else:
            s.weight = tint * (g_ratio / (eta * eta))
    return s


# --- Thin-walled dielectric (a shell with no inside) --------------------------------------------------
@ti.func
def thin_reflectance(cos_i, ior):
    """A thin slab's reflectance with its internal reflections summed: F + (1 - F)^2 F / (1 - F^2)
    = 2 F / (1 + F) (pbrt-v4's ThinDielectricBxDF), F the interface's Fresnel reflectance."""
    f, _ = mf.fresnel_dielectric(ti.math.clamp(cos_i, 0.0, 1.0), ior)
    return 2.0 * f / (1.0 + f)


@ti.func
def _mirrored(w):
    return vec3(w.x, w.y, -w.z)


@ti.func
def thin_dielectric_eval(tint, alpha, ior, wo, wi, model=mf.GGX, alpha_v=mf.ISOTROPIC):
    """Rough thin wall: a GGX reflection lobe whose microfacets reflect with the slab's reflectance
    R(wo.h) and pass the rest straight through, i.e. into the reflected direction mirrored to the
    far side (no bending, no 1 / eta^2: the light leaves into the medium it came from).
    R + T = 1 per microfacet, so the lobe's albedo is a white GGX mirror's."""
    value = vec3(0.0)
    pdf = 0.0
    if alpha > 0.0 and wi.z != 0.0:
        wr = vec3(wi.x, wi.y, ti.abs(wi.z))
        h = ti.math.normalize(wo + wr)
        cos_oh = wo.dot(h)
        if cos_oh > 0.0:
            r = thin_reflectance(cos_oh, ior)
            f_cos = mf.d(h, alpha, model, alpha_v) * mf.g2(wo, wr, alpha, model, alpha_v) / (4.0 * wo.z)
            lobe_pdf = mf.normal_pdf(wo, h, alpha, model, alpha_v) / (4.0 * cos_oh)
            if wi.z > 0.0:
                value = vec3(r * f_cos)
                pdf = r * lobe_pdf
            else:
                value = tint * ((1.0 - r) * f_cos)
                pdf = (1.0 - r) * lobe_pdf
    return value, pdf


@ti.func
def thin_dielectric_sample(tint, alpha, ior, wo, u1, u2, model=mf.GGX, alpha_v=mf.ISOTROPIC):
    """Reflect with the slab's reflectance, else pass straight through (smooth: along -wo)."""
    s = BsdfSample(wi=vec3(0.0, 0.0, 1.0), weight=vec3(0.0), pdf=0.0, delta=1, valid=1)
    h = vec3(0.0, 0.0, 1.0)
    if alpha > 0.0:
        h = mf.sample_normal(wo, alpha, u2, model, alpha_v)
        s.delta = 0
    cos_oh = wo.dot(h)
    facing_away = cos_oh <= 0.0  # (a guard: rounding can leave a sampled normal facing away from wo)
    r = thin_reflectance(cos_oh, ior)
    wr = mf.reflect(wo, h)
    if wr.z <= 0.0 or facing_away:
        s.valid = 0
    else:
        g_ratio = 1.0
        lobe_pdf = 1.0
        if alpha > 0.0:
            g_ratio = mf.sampled_weight(wo, wr, h, alpha, model, alpha_v)
            lobe_pdf = mf.normal_pdf(wo, h, alpha, model, alpha_v) / (4.0 * cos_oh)
        if u1 < r:
            s.wi = wr
            s.weight = vec3(g_ratio)
            s.pdf = r * lobe_pdf
        else:
            s.wi = _mirrored(wr)
            s.weight = tint * g_ratio
            s.pdf = (1.0 - r) * lobe_pdf
    return s


# --- The principled model's dielectric coat -------------------------------------------------------------
@ti.func
def coat_specular_eval(ior, alpha, wo, wi):
    h = ti.math.normalize(wo + wi)
    f, _ = mf.fresnel_dielectric(ti.max(wo.dot(h), 1e-6), ior)
    return ggx_reflection_eval(vec3(f), alpha, wo, wi)

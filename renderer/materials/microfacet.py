"""Microfacet distributions: GGX (Trowbridge-Reitz) with visible-normal sampling, and Beckmann.

All vectors are in the local shading frame (z = normal). `alpha` is the distribution's width
(roughness^2). A material's microfacet model (the row's `microfacet`, one of MODELS) picks the
distribution and the masking-shadowing form:
  GGX (Lantern's default): Smith's height-correlated G2 = 1 / (1 + Lambda(wo) + Lambda(wi)),
      normals drawn from the visible normals (Heitz 2018);
  GGX_SEPARABLE: GGX with Smith's separable G2 = G1(wo) G1(wi), Mitsuba 3's and Walter et al.'s;
  BECKMANN: Beckmann's Gaussian slopes with the separable G2 and Walter et al.'s rational fit
      of G1 (under 0.35% from the exact one), as Mitsuba 3 has it; normals drawn from the visible
      normals as Mitsuba 3 draws them (Jakob 2014's numerical inversion), so that a sample's
      weight is G2 / G1(wo), about 1 at most: drawn from D(h) cos(h), the weight grew as
      |wo.h| / wo.z at grazing wo, and rough glass seen edge-on had fireflies Mitsuba's has not.
The `model` arguments default to GGX, which compiles to the GGX code alone.
"""
import taichi as ti

from renderer.materials.kinds import MICROFACET_MODELS as MODELS
from renderer.sampling.warps import PI

GGX, GGX_SEPARABLE, BECKMANN = MODELS["ggx"], MODELS["ggx_separable"], MODELS["beckmann"]
# An `alpha_v` argument below 0: the distribution is isotropic, alpha wide in every direction;
# otherwise alpha is its width along the frame's x axis (the surface's dp/du) and alpha_v along y.
ISOTROPIC = -1.0
_INV_SQRT_PI = 0.5641895835477563


@ti.func
def ggx_d(h, alpha, alpha_v=ISOTROPIC):
    value = 0.0
    if alpha_v < 0.0:
        a2 = alpha * alpha
        t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z
        value = 1.0 / (PI * a2 * t * t)
    else:
        t = h.x * h.x / (alpha * alpha) + h.y * h.y / (alpha_v * alpha_v) + h.z * h.z
        value = 1.0 / (PI * alpha * alpha_v * t * t)
    return value


@ti.func
def _projected_alpha2_xy(w, alpha, alpha_v):
    """alpha^2 (w.x^2 + w.y^2), the width along w's azimuth squared times sin^2 (anisotropic:
    alpha_u^2 w.x^2 + alpha_v^2 w.y^2)."""
    value = 0.0
    if alpha_v < 0.0:
        value = alpha * alpha * (w.x * w.x + w.y * w.y)
    else:
        value = alpha * alpha * w.x * w.x + alpha_v * alpha_v * w.y * w.y
    return value


@ti.func
def smith_lambda(w, alpha, alpha_v=ISOTROPIC):
    # Lambda = (sqrt(1 + alpha^2 tan^2) - 1) / 2, written without tan so that z -> 0 gives a large
    # finite value; callers reject z <= 0 before this is reached.
    z2 = ti.max(w.z * w.z, 1e-20)
    return 0.5 * (ti.sqrt(1.0 + _projected_alpha2_xy(w, alpha, alpha_v) / z2) - 1.0)


@ti.func
def smith_g1(w, alpha, alpha_v=ISOTROPIC):
    return 1.0 / (1.0 + smith_lambda(w, alpha, alpha_v))


@ti.func
def smith_g2(wo, wi, alpha, alpha_v=ISOTROPIC):
    return 1.0 / (1.0 + smith_lambda(wo, alpha, alpha_v) + smith_lambda(wi, alpha, alpha_v))


@ti.func
def sample_visible_normal(wo, alpha, u, alpha_v=ISOTROPIC):
    """Heitz 2018, 'Sampling the GGX distribution of visible normals'. wo.z must be > 0."""
    ay = alpha if alpha_v < 0.0 else alpha_v
    vh = ti.math.normalize(ti.math.vec3(alpha * wo.x, ay * wo.y, wo.z))
    lensq = vh.x * vh.x + vh.y * vh.y
    t1 = ti.math.vec3(1.0, 0.0, 0.0)
    if lensq > 0.0:
        t1 = ti.math.vec3(-vh.y, vh.x, 0.0) / ti.sqrt(lensq)
    t2 = vh.cross(t1)
    r = ti.sqrt(u.x)
    phi = 2.0 * PI * u.y
    p1 = r * ti.cos(phi)
    p2 = r * ti.sin(phi)
    s = 0.5 * (1.0 + vh.z)
    p2 = (1.0 - s) * ti.sqrt(ti.max(0.0, 1.0 - p1 * p1)) + s * p2
    nh = p1 * t1 + p2 * t2 + ti.sqrt(ti.max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh
    return ti.math.normalize(ti.math.vec3(alpha * nh.x, ay * nh.y, ti.max(1e-6, nh.z)))


@ti.func
def visible_normal_pdf(wo, h, alpha, alpha_v=ISOTROPIC):
    """Density of h under sample_visible_normal: G1(wo) max(0, wo.h) D(h) / wo.z."""
    return smith_g1(wo, alpha, alpha_v) * ti.max(0.0, wo.dot(h)) * ggx_d(h, alpha, alpha_v) / wo.z


# --- Beckmann ----------------------------------------------------------------------------------------
@ti.func
def beckmann_d(h, alpha, alpha_v=ISOTROPIC):
    cos2 = h.z * h.z
    d = 0.0
    if cos2 > 0.0:
        if alpha_v < 0.0:
            tan2 = (h.x * h.x + h.y * h.y) / cos2
            d = ti.exp(-tan2 / (alpha * alpha)) / (PI * alpha * alpha * cos2 * cos2)
        else:
            e = (h.x * h.x / (alpha * alpha) + h.y * h.y / (alpha_v * alpha_v)) / cos2
            d = ti.exp(-e) / (PI * alpha * alpha_v * cos2 * cos2)
    return d


@ti.func
def beckmann_g1(w, alpha, alpha_v=ISOTROPIC):
    """Walter et al. 2007's rational fit of Beckmann's Smith G1, a = 1 / (alpha tan(theta)) with
    alpha the width along w's azimuth."""
    g = 1.0
    xy = _projected_alpha2_xy(w, alpha, alpha_v)
    if xy > 0.0:
        a = ti.abs(w.z) / ti.sqrt(xy)
        if a < 1.6:
            g = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    return g


@ti.func
def _erf(x):
    """Abramowitz and Stegun 7.1.26 (absolute error under 1.5e-7)."""
    a = ti.abs(x)
    t = 1.0 / (1.0 + 0.3275911 * a)
    poly = (((1.061405429 * t - 1.453152027) * t + 1.421413741) * t - 0.284496736) * t + 0.254829592
    y = 1.0 - poly * t * ti.exp(-a * a)
    if x < 0.0:
        y = -y
    return y


@ti.func
def _erfinv(x):
    """Giles 2010's single-precision inverse error function, x in (-1, 1)."""
    w = -ti.log((1.0 - x) * (1.0 + x))
    p = 0.0
    if w < 5.0:
        w = w - 2.5
        p = 2.81022636e-08
        p = 3.43273939e-07 + p * w
        p = -3.5233877e-06 + p * w
        p = -4.39150654e-06 + p * w
        p = 0.00021858087 + p * w
        p = -0.00125372503 + p * w
        p = -0.00417768164 + p * w
        p = 0.246640727 + p * w
        p = 1.50140941 + p * w
    else:
        w = ti.sqrt(w) - 3.0
        p = -0.000200214257
        p = 0.000100950558 + p * w
        p = 0.00134934322 + p * w
        p = -0.00367342844 + p * w
        p = 0.00573950773 + p * w
        p = -0.0076224613 + p * w
        p = 0.00943887047 + p * w
        p = 1.00167406 + p * w
        p = 2.83297682 + p * w
    return p * x


@ti.func
def beckmann_visible_g1(w, alpha, alpha_v=ISOTROPIC):
    """Beckmann's exact Smith G1 = 1 / (1 + Lambda), Lambda = (erf(a) - 1) / 2 + exp(-a^2) /
    (2 a sqrt(pi)), a = 1 / (alpha tan(theta)): the normalisation of the visible normals that
    beckmann_sample_visible_normal draws (the masking in f stays the rational fit, as Mitsuba's)."""
    lam = 0.0
    xy = _projected_alpha2_xy(w, alpha, alpha_v)
    if xy > 0.0:
        a = ti.abs(w.z) / ti.sqrt(xy)
        if a < 8.0:  # beyond, Lambda < 1e-29
            lam = ti.max(0.0, 0.5 * (_erf(a) - 1.0) + ti.exp(-a * a) * _INV_SQRT_PI / (2.0 * ti.max(a, 1e-30)))
    return 1.0 / (1.0 + lam)


@ti.func
def beckmann_sample_visible_normal(wo, alpha, u, alpha_v=ISOTROPIC):
    """A normal drawn from Beckmann's visible normals, density G1(wo) max(0, wo.h) D(h) / wo.z
    (G1 the exact one, beckmann_visible_g1): Mitsuba 3's routine (Jakob 2014, 'An improved
    visible normal sampling routine for the Beckmann distribution'): wo stretched to unit width,
    the slope across wo's plane by three Newton steps on its CDF in erf's domain, the other
    slope Gaussian, then rotated and unstretched. wo.z must be > 0."""
    ay = alpha if alpha_v < 0.0 else alpha_v
    ws = ti.math.normalize(ti.math.vec3(alpha * wo.x, ay * wo.y, wo.z))
    cos_i = ws.z
    sin_i = ti.sqrt(ti.max(0.0, 1.0 - cos_i * cos_i))
    tan_i = sin_i / cos_i
    cot_i = ti.min(cos_i / ti.max(sin_i, 1e-30), 1e4)  # (beyond, erf is 1 and exp(-cot^2) 0 in float32)
    cos_phi = 1.0
    sin_phi = 0.0
    if sin_i > 0.0:
        r = ti.sqrt(ws.x * ws.x + ws.y * ws.y)
        if r > 0.0:
            cos_phi = ws.x / r
            sin_phi = ws.y / r
    u1 = ti.math.clamp(u.x, 1e-6, 1.0 - 1e-6)
    u2 = ti.math.clamp(u.y, 1e-6, 1.0 - 1e-6)
    # The slope's CDF, in x = erf(slope) up to erf(cot): (1 + x + tan exp(-slope^2) / sqrt(pi)) / norm.
    maxval = _erf(cot_i)
    x = maxval - (maxval + 1.0) * _erf(ti.sqrt(-ti.log(u1)))  # the exact solution at grazing incidence
    target = u1 * (1.0 + maxval + _INV_SQRT_PI * tan_i * ti.exp(-cot_i * cot_i))
    for _ in ti.static(range(3)):
        slope = _erfinv(x)
        value = 1.0 + x + _INV_SQRT_PI * tan_i * ti.exp(-slope * slope) - target
        x -= value / (1.0 - slope * tan_i)
    sx = _erfinv(x)
    sy = _erfinv(2.0 * u2 - 1.0)
    mx = (cos_phi * sx - sin_phi * sy) * alpha
    my = (sin_phi * sx + cos_phi * sy) * ay
    return ti.math.normalize(ti.math.vec3(-mx, -my, 1.0))


# --- A material's model: the distribution and masking a row names -----------------------------------
@ti.func
def row_model(bsdf: ti.template(), mat):
    """A material's microfacet model: its row's, or GGX (a constant the compiler folds) in scenes
    whose rows name no other."""
    return mat.microfacet if ti.static(bsdf.features.has_microfacet_models) else GGX


@ti.func
def d(h, alpha, model=GGX, alpha_v=ISOTROPIC):
    value = 0.0
    if model == BECKMANN:
        value = beckmann_d(h, alpha, alpha_v)
    else:
        value = ggx_d(h, alpha, alpha_v)
    return value


@ti.func
def g1(w, alpha, model=GGX, alpha_v=ISOTROPIC):
    value = 0.0
    if model == BECKMANN:
        value = beckmann_g1(w, alpha, alpha_v)
    else:
        value = smith_g1(w, alpha, alpha_v)
    return value


@ti.func
def g2(wo, wi, alpha, model=GGX, alpha_v=ISOTROPIC):
    value = 0.0
    if model == GGX:
        value = smith_g2(wo, wi, alpha, alpha_v)
    else:
        value = g1(wo, alpha, model, alpha_v) * g1(wi, alpha, model, alpha_v)
    return value


@ti.func
def sample_normal(wo, alpha, u, model=GGX, alpha_v=ISOTROPIC):
    """A microfacet normal as the model draws them (see normal_pdf)."""
    h = ti.math.vec3(0.0, 0.0, 1.0)
    if model == BECKMANN:
        h = beckmann_sample_visible_normal(wo, alpha, u, alpha_v)
    else:
        h = sample_visible_normal(wo, alpha, u, alpha_v)
    return h


@ti.func
def normal_pdf(wo, h, alpha, model=GGX, alpha_v=ISOTROPIC):
    """The density of sample_normal's h: the model's visible normals."""
    pdf = 0.0
    if model == BECKMANN:
        pdf = beckmann_visible_g1(wo, alpha, alpha_v) * ti.max(0.0, wo.dot(h)) * beckmann_d(h, alpha, alpha_v) / wo.z
    else:
        pdf = visible_normal_pdf(wo, h, alpha, alpha_v)
    return pdf


@ti.func
def sampled_weight(wo, wi, h, alpha, model=GGX, alpha_v=ISOTROPIC):
    """D G2 |wo.h| / (wo.z pdf(h)): the weight of a direction sampled through h, Fresnel and
    tint aside. Visible normals leave G2 / G1(wo) (Beckmann: its exact G1 over the fitted G2)."""
    w = 0.0
    if model == BECKMANN:
        w = g2(wo, wi, alpha, model, alpha_v) / beckmann_visible_g1(wo, alpha, alpha_v)
    else:
        w = g2(wo, wi, alpha, model, alpha_v) / smith_g1(wo, alpha, alpha_v)
    return w


@ti.func
def row_alpha_v(bsdf: ti.template(), mat):
    """A material's width along its frame's y axis, or ISOTROPIC (a constant the compiler folds)
    in scenes whose rows are all isotropic."""
    return mat.alpha_v if ti.static(bsdf.features.has_anisotropy) else ISOTROPIC


@ti.func
def fresnel_schlick(f0, cos_theta):
    m = ti.math.clamp(1.0 - cos_theta, 0.0, 1.0)
    m2 = m * m
    return f0 + (1.0 - f0) * (m2 * m2 * m)


@ti.func
def fresnel_dielectric(cos_i, eta):
    """Exact unpolarised Fresnel reflectance. eta = n_transmitted / n_incident, cos_i in (0, 1].

    Returns (F, cos_t); F = 1 and cos_t = 0 under total internal reflection.
    """
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    f = 1.0
    cos_t = 0.0
    if sin2_t < 1.0:
        cos_t = ti.sqrt(1.0 - sin2_t)
        rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
        rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
        f = 0.5 * (rs * rs + rp * rp)
    return f, cos_t


@ti.func
def fresnel_dielectric_either_side(cos_i, eta):
    """fresnel_dielectric for light from either side, as Mitsuba's fresnel(): cos_i < 0 is from
    inside (the index then inverted). Returns (F, signed cos_t, eta_it, eta_ti): cos_t on the far
    side (negative for cos_i > 0), eta_it = n_t / n_i and eta_ti its inverse."""
    outside = cos_i >= 0.0
    eta_it = eta if outside else 1.0 / eta
    eta_ti = 1.0 / eta if outside else eta
    cos_t_sqr = 1.0 - (1.0 - cos_i * cos_i) * (eta_ti * eta_ti)
    ci = ti.abs(cos_i)
    ct = ti.sqrt(ti.max(cos_t_sqr, 0.0))
    r = 1.0
    if eta == 1.0:
        r = 0.0
    elif ci > 0.0:
        a_s = (ci - eta_it * ct) / (ci + eta_it * ct)
        a_p = (ct - eta_it * ci) / (ct + eta_it * ci)
        r = 0.5 * (a_s * a_s + a_p * a_p)
    return r, (-ct if cos_i >= 0.0 else ct), eta_it, eta_ti


@ti.func
def _fresnel_conductor_channel(c, s2, eta, k):
    """One channel of fresnel_conductor: c = cos_i, s2 = sin_i^2."""
    # u = sqrt((eta + i k)^2 - sin^2) = a + i b, the square root taken from whichever of a, b is
    # the larger, so that neither comes from a difference of nearly equal numbers (large k).
    t = eta * eta - k * k - s2
    y = 2.0 * eta * k
    modulus = ti.sqrt(t * t + y * y)
    a = 0.0
    b = 0.0
    if t >= 0.0:
        a = ti.sqrt(0.5 * (modulus + t))
        b = y / ti.max(2.0 * a, 1e-30)
    else:
        b = ti.sqrt(0.5 * (modulus - t))
        a = y / (2.0 * b)
    # |rs|^2 = |c - u|^2 / |c + u|^2, |rp|^2 = |rs|^2 |a c - s^2 - i b c|^2 / |a c + s^2 + i b c|^2:
    # sums of squares, no cancellation; at grazing (c = 0) both are exactly 1. A denominator is 0
    # only where u = 0 as well (eta = 1, k = 0 at grazing; eta = k = 0 head-on): there the limit,
    # 1 and |rp| = |rs|, is used.
    b2 = b * b
    rs = 1.0
    den_s = (a + c) * (a + c) + b2
    if den_s > 0.0:
        rs = ((a - c) * (a - c) + b2) / den_s
    p_minus = a * c - s2
    p_plus = a * c + s2
    bc2 = b2 * c * c
    ratio = 1.0
    den_p = p_plus * p_plus + bc2
    if den_p > 0.0:
        ratio = (p_minus * p_minus + bc2) / den_p
    return 0.5 * rs * (1.0 + ratio)


@ti.func
def head_on_reflectance(eta, k):
    """fresnel_conductor at normal incidence, ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2) (vec3)."""
    return ((eta - 1.0) ** 2 + k * k) / ((eta + 1.0) ** 2 + k * k)


@ti.func
def fresnel_conductor(cos_i, eta, k):
    """Exact unpolarised Fresnel reflectance at an interface to a conductor of complex index
    eta + i k (relative to the outside; vec3 per channel), cos_i in [0, 1]. k = 0 is the dielectric
    Fresnel (total internal reflection included for eta < 1); normal incidence gives
    ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2). f32-stable for k = 0, for large k and at grazing
    angles (the p-polarised factor is written without dividing by cos_i)."""
    c = ti.math.clamp(cos_i, 0.0, 1.0)
    s2 = 1.0 - c * c
    f = ti.math.vec3(0.0)
    for i in ti.static(range(3)):
        f[i] = _fresnel_conductor_channel(c, s2, eta[i], k[i])
    return f


@ti.func
def reflect(wo, h):
    return 2.0 * wo.dot(h) * h - wo


@ti.func
def refract(wo, h, eta, cos_t):
    """Refract wo (on the side h points to) through the microfacet h; eta = n_t / n_i."""
    return -wo / eta + (wo.dot(h) / eta - cos_t) * h

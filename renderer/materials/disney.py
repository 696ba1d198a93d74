"""The `disney` kind: Disney's principled BSDF (Burley 2012, 2015) exactly as Mitsuba 3 defines it
in its `principled` plugin and, for a row with `thin`, its `principledthin`, so that Mitsuba's
scenes render alike. Lobe module of renderer/materials/kinds.py (see diffuse.py).

Thick (a closed surface with an inside of index `ior`):
  diffuse    (1 - metallic)(1 - spec_trans) base/pi, Burley's retro-reflection, and Hanrahan-
             Krueger's fake subsurface blended in by `flatness`, front side only;
  sheen      sheen (1 - metallic) Schlick(cos_d), tinted towards the base's hue by sheen_tint;
  specular   anisotropic GGX (alpha = roughness^2 stretched by `anisotropic`, at least 0.001) with
             Smith's separable masking; on the front its Fresnel blends the dielectric one, a
             Schlick tinted by spec_tint, and for metals Schlick from base_color; from inside,
             the dielectric Fresnel times the transmitting weight;
  transmission  sqrt(base) (1 - metallic) spec_trans times the rough dielectric's refraction;
  clearcoat  0.25 clearcoat Schlick(0.04) GTR1(lerp(0.1, 0.001, clearcoat_gloss)) with Smith
             G1(alpha 0.25) masking, front side only, written as Mitsuba writes it.
Thin (`thin`, two-sided and symmetric: both sides shade as the front):
  specular reflection and a transmission that mirrors it through the sheet (no bending; its width
  scaled by 0.65 eta - 0.35, Burley 2015 fig. 15), each half of spec_trans; diffuse as above
  times (1 - diff_trans / 2) and Lambertian transmission times diff_trans / 2.

Lobes are chosen as Mitsuba chooses them (its sampling rates left at 1), and `sample` returns
eval / pdf of the whole mixture, as Mitsuba does. A thick row's vectors are taken into Mitsuba's
frame, whose z is the surface's outward normal (Lantern's frame faces wo); every formula is then
Mitsuba's. Where Mitsuba's vectorised and scalar variants differ (the sheen is evaluated where
only its own mask holds, also with no diffuse lobe), the vectorised variants' reading is taken.
"""
import taichi as ti

from renderer.materials import microfacet as mf
from renderer.materials.kinds import LobeFlags
from renderer.materials.lobes import BsdfSample, invalid_sample
from renderer.sampling.warps import INV_PI, PI, cosine_hemisphere

vec3 = ti.math.vec3
MIN_WIDTH = 0.001  # Mitsuba's floor on both GGX widths
CLEARCOAT_MASKING_ALPHA = 0.25


# --- Mitsuba's helpers ------------------------------------------------------------------------------------
@ti.func
def _mulsign(v, s):
    """v times the sign of s (+ for s = 0), Mitsuba's mulsign."""
    return v if s >= 0.0 else -v


@ti.func
def _mitsuba_frame(v, entering):
    """A local vector of Lantern's frame (z towards wo) in Mitsuba's (z along the outward normal)."""
    return v if entering else vec3(v.x, v.y, -v.z)


@ti.func
def _refract(wi, m, cos_t, eta_ti):
    return m * (wi.dot(m) * eta_ti + cos_t) - wi * eta_ti


@ti.func
def _compatible(m, wi, wo, cos_i, reflection: ti.template()):
    """Mitsuba's mac_mic_compatibility: wi and wo on the sides of microfacet m that a reflection
    (or a refraction) through it puts them on."""
    m_side = _mulsign(m, cos_i)
    ok = wi.dot(m_side) > 0.0
    if ti.static(reflection):
        ok = ok and wo.dot(m_side) > 0.0
    else:
        ok = ok and wo.dot(-m_side) > 0.0
    return ok


@ti.func
def _widths(anisotropic, roughness):
    """Mitsuba's calc_dist_params: the GGX widths along u and v."""
    r2 = roughness * roughness
    aspect = ti.sqrt(1.0 - 0.9 * anisotropic)
    return ti.max(MIN_WIDTH, r2 / aspect), ti.max(MIN_WIDTH, r2 * aspect)


@ti.func
def _ggx_d(m, ax, ay):
    t = (m.x / ax) ** 2 + (m.y / ay) ** 2 + m.z * m.z
    d = 1.0 / (PI * ax * ay * t * t)
    return d if d * m.z > 1e-20 else 0.0


@ti.func
def _ggx_g1(v, m, ax, ay):
    """Smith's G1 for GGX, 0 where v sees the back of m."""
    xy = (ax * v.x) ** 2 + (ay * v.y) ** 2
    g = 2.0 / (1.0 + ti.sqrt(1.0 + xy / (v.z * v.z)))
    if xy == 0.0:
        g = 1.0
    if v.dot(m) * v.z <= 0.0:
        g = 0.0
    return g


@ti.func
def _visible_normal_pdf(w, m, ax, ay):
    """The density of m among the normals visible from w (w.z > 0)."""
    return _ggx_d(m, ax, ay) * _ggx_g1(w, m, ax, ay) * ti.abs(w.dot(m)) / w.z


@ti.func
def _gtr1_d(m, a):
    a2 = a * a
    c = m.z
    d = (a2 - 1.0) / (PI * ti.log(a2) * (1.0 + (a2 - 1.0) * c * c))
    return d if d * c > 1e-20 else 0.0


@ti.func
def _gtr1_sample(u, a):
    a2 = a * a
    cos2 = (1.0 - ti.pow(a2, 1.0 - u.y)) / (1.0 - a2)
    sin_t = ti.sqrt(ti.max(0.0, 1.0 - cos2))
    phi = 2.0 * PI * u.x
    return vec3(ti.cos(phi) * sin_t, ti.sin(phi) * sin_t, ti.sqrt(ti.max(0.0, cos2)))


@ti.func
def _clearcoat_g1(v, m):
    """Mitsuba's smith_ggx1 with the clear coat's fixed width."""
    c = ti.abs(v.z)
    tan2 = (1.0 - c * c) / (c * c)
    g = 2.0 / (1.0 + ti.sqrt(1.0 + CLEARCOAT_MASKING_ALPHA ** 2 * tan2))
    if v.z == 1.0:
        g = 1.0
    if v.dot(m) * v.z <= 0.0:
        g = 0.0
    return g


@ti.func
def _schlick_weight(c):
    m = ti.math.clamp(1.0 - c, 0.0, 1.0)
    return m * m * m * m * m


@ti.func
def _schlick(r0, cos_i, eta):
    """Mitsuba's calc_schlick: Schlick's Fresnel from r0 (a number or a colour), on the denser
    side taken at the transmitted angle."""
    eta_it = eta if cos_i >= 0.0 else 1.0 / eta
    eta_ti = 1.0 / eta if cos_i >= 0.0 else eta
    cos_t = ti.sqrt(ti.max(1.0 - (1.0 - cos_i * cos_i) * (eta_ti * eta_ti), 0.0))
    w = _schlick_weight(ti.abs(cos_i)) if eta_it > 1.0 else _schlick_weight(cos_t)
    return w * (1.0 - r0) + r0


@ti.func
def _r0(eta):
    return ((eta - 1.0) / (eta + 1.0)) ** 2


@ti.func
def _hue(base):
    """The base colour divided by its luminance (white where it is black): what the tints blend to."""
    lum = 0.212671 * base.x + 0.715160 * base.y + 0.072169 * base.z
    return base / lum if lum > 0.0 else vec3(1.0)


@ti.func
def _diffuse(mat, cos_i, cos_o, cos_d):
    """Burley's diffuse with retro-reflection, blended with the fake subsurface by flatness, times
    base/pi |cos_o| (lobe weights aside), and the sheen's Schlick(cos_d) term (weights aside)."""
    fo = _schlick_weight(ti.abs(cos_o))
    fi = _schlick_weight(ti.abs(cos_i))
    f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo)
    rr = 2.0 * mat.roughness * cos_d * cos_d
    f_retro = rr * (fo + fi + fo * fi * (rr - 1.0))
    fss = (1.0 + (0.5 * rr - 1.0) * fo) * (1.0 + (0.5 * rr - 1.0) * fi)
    f_ss = 1.25 * (fss * (1.0 / (ti.abs(cos_o) + ti.abs(cos_i)) - 0.5) + 0.5)
    diffuse = ti.abs(cos_o) * mat.base_color * INV_PI * ti.math.mix(f_diff + f_retro, f_ss, mat.flatness)
    return diffuse


@ti.func
def _sheen(mat, cos_o, cos_d):
    tint = 1.0 + mat.sheen_tint * (_hue(mat.base_color) - 1.0)
    return mat.sheen * _schlick_weight(ti.abs(cos_d)) * tint * ti.abs(cos_o)


@ti.func
def _refraction_probability(spec_trans, btdf, f, front):
    """The unnormalised chance of drawing the refraction: from inside, all that the Fresnel does not
    reflect, where the surface transmits at all (Mitsuba's has_spec_trans)."""
    p = btdf * (1.0 - f)
    if not front:
        p = 1.0 - f if spec_trans > 0.0 else 0.0
    return p


# --- thick: Mitsuba's principled ----------------------------------------------------------------------
@ti.func
def _thick(mat, wi, wo):
    """(f |cos wo|, pdf) of Mitsuba's principled, wi towards the viewer and wo the scattered
    direction, both in Mitsuba's frame."""
    value = vec3(0.0)
    pdf = 0.0
    cos_i = wi.z
    if cos_i != 0.0:
        metallic, spec_trans, clearcoat, eta = mat.metallic, mat.transmission, mat.clearcoat, mat.ior
        brdf = (1.0 - metallic) * (1.0 - spec_trans)
        btdf = (1.0 - metallic) * spec_trans
        cos_o = wo.z
        reflect = cos_i * cos_o > 0.0
        refract = cos_i * cos_o < 0.0
        front = cos_i > 0.0
        eta_path = eta if front else 1.0 / eta
        wh = ti.math.normalize(wi + wo * (1.0 if reflect else eta_path))
        wh = _mulsign(wh, wh.z)
        ax, ay = _widths(mat.anisotropic, mat.roughness)
        cos_ih, cos_oh = wi.dot(wh), wo.dot(wh)
        f, _, _, _ = mf.fresnel_dielectric_either_side(cos_ih, eta)
        reflection_ok = reflect and _compatible(wh, wi, wo, cos_i, True)
        refraction_ok = refract and _compatible(wh, wi, wo, cos_i, False)
        d = _ggx_d(wh, ax, ay)
        g = _ggx_g1(wi, wh, ax, ay) * _ggx_g1(wo, wh, ax, ay)
        cc_alpha = ti.math.mix(0.1, 0.001, mat.clearcoat_gloss)
        if reflection_ok and f > 0.0:
            fresnel = vec3(btdf * f)
            if front:  # Mitsuba's principled_fresnel
                tinted = _schlick(_hue(mat.base_color) * _r0(eta), cos_ih, eta)
                fresnel = ((1.0 - metallic) * (1.0 - mat.spec_tint) * f + metallic * _schlick(mat.base_color, cos_ih, eta)
                           + (1.0 - metallic) * mat.spec_tint * tinted)
            value += fresnel * d * g / (4.0 * ti.abs(cos_i))
        if btdf > 0.0 and refraction_ok and f < 1.0:
            # The radiance form: Mitsuba's eta_path^2 and its 1 / eta_path^2 cancel.
            denom = cos_ih + eta_path * cos_oh
            value += ti.sqrt(mat.base_color) * btdf * ti.abs((1.0 - f) * d * g * cos_ih * cos_oh / (cos_i * denom * denom))
        if clearcoat > 0.0 and reflection_ok and front:
            value += (clearcoat * 0.25 * _schlick(0.04, cos_ih, eta) * _gtr1_d(wh, cc_alpha)
                      * _clearcoat_g1(wi, wh) * _clearcoat_g1(wo, wh) * ti.abs(cos_o))
        if reflect and front:
            cos_d = wh.dot(wo)
            if brdf > 0.0:
                value += brdf * _diffuse(mat, cos_i, cos_o, cos_d)
            if mat.sheen > 0.0 and 1.0 - metallic > 0.0:
                value += (1.0 - metallic) * _sheen(mat, cos_o, cos_d)
        # The lobes' sampling probabilities at this wh, and the densities.
        p_reflect = (1.0 - btdf * (1.0 - f)) if front else f
        p_refract = _refraction_probability(spec_trans, btdf, f, front)
        p_clearcoat = 0.25 * clearcoat if front else 0.0
        p_diffuse = brdf if front else 0.0
        total = p_reflect + p_refract + p_clearcoat + p_diffuse
        dwh_dwo = ti.abs(1.0 / (4.0 * cos_oh))
        if not reflect:
            dwh_dwo = ti.abs(eta_path * eta_path * cos_oh / (cos_ih + eta_path * cos_oh) ** 2)
        w_up = _mulsign(wi, cos_i)
        if reflection_ok:
            pdf += (p_reflect * _visible_normal_pdf(w_up, wh, ax, ay)
                    + p_clearcoat * ti.max(wh.z, 0.0) * _gtr1_d(wh, cc_alpha)) * dwh_dwo
        if reflect:
            pdf += p_diffuse * cos_o * INV_PI
        if refraction_ok:
            pdf += p_refract * _visible_normal_pdf(w_up, wh, ax, ay) * dwh_dwo
        pdf /= total
    return value, pdf


@ti.func
def _thick_direction(mat, wi, u1, u2):
    """(wo, valid): a direction drawn as Mitsuba's principled draws it (Mitsuba's frame)."""
    metallic, spec_trans, clearcoat = mat.metallic, mat.transmission, mat.clearcoat
    brdf = (1.0 - metallic) * (1.0 - spec_trans)
    btdf = (1.0 - metallic) * spec_trans
    cos_i = wi.z
    front = cos_i > 0.0
    ax, ay = _widths(mat.anisotropic, mat.roughness)
    m = mf.sample_visible_normal(_mulsign(wi, cos_i), ax, u2, ay)
    f, cos_t, _, eta_ti = mf.fresnel_dielectric_either_side(wi.dot(m), mat.ior)
    p_refract = _refraction_probability(spec_trans, btdf, f, front)
    p_clearcoat = 0.25 * clearcoat if front else 0.0
    p_diffuse = brdf if front else 0.0
    total = ((1.0 - btdf * (1.0 - f)) if front else f) + p_refract + p_clearcoat + p_diffuse
    u = u1 * total
    wo = vec3(0.0, 0.0, 1.0)
    valid = front or btdf > 0.0
    if u < p_diffuse:
        wo = cosine_hemisphere(u2)
        valid = valid and cos_i * wo.z > 0.0
    elif u < p_diffuse + p_clearcoat:
        m_cc = _gtr1_sample(u2, ti.math.mix(0.1, 0.001, mat.clearcoat_gloss))
        wo = mf.reflect(wi, m_cc)
        valid = valid and _compatible(m_cc, wi, wo, cos_i, True) and cos_i * wo.z > 0.0
    elif u < p_diffuse + p_clearcoat + p_refract:
        wo = _refract(wi, m, cos_t, eta_ti)
        valid = valid and _compatible(m, wi, wo, cos_i, False) and cos_i * wo.z < 0.0
    else:
        wo = mf.reflect(wi, m)
        valid = valid and _compatible(m, wi, wo, cos_i, True) and cos_i * wo.z > 0.0
    return wo, valid


# --- thin: Mitsuba's principledthin ---------------------------------------------------------------------
@ti.func
def _thin(mat, wi_any, wo_any):
    """(f |cos wo|, pdf) of Mitsuba's principledthin; the sheet is symmetric, so either frame."""
    value = vec3(0.0)
    pdf = 0.0
    cos_i = wi_any.z
    if cos_i != 0.0:
        spec_trans, eta = mat.transmission, mat.ior
        diff_trans = 0.5 * mat.diff_trans  # Mitsuba's range 0..2, made 0..1
        wi = _mulsign(wi_any, cos_i)
        wo = _mulsign(wo_any, cos_i)
        cos_o = wo.z
        reflect = cos_o > 0.0
        refract = cos_o < 0.0
        wo_r = vec3(wo.x, wo.y, ti.abs(wo.z))
        wh = ti.math.normalize(wi + wo_r)
        reflection_ok = reflect and _compatible(wh, wi, wo, wi.z, True)
        refraction_ok = refract and _compatible(wh, wi, wo, wi.z, False)
        ax, ay = _widths(mat.anisotropic, mat.roughness)
        tx, ty = _widths(mat.anisotropic, (0.65 * eta - 0.35) * mat.roughness)
        f, _, _, _ = mf.fresnel_dielectric_either_side(wi.dot(wh), eta)
        if spec_trans > 0.0 and reflection_ok:
            tinted = _schlick(_hue(mat.base_color) * _r0(eta), wi.dot(wh), eta)
            fresnel = ti.math.mix(vec3(f), tinted, mat.spec_tint)  # Mitsuba's thin_fresnel
            g = _ggx_g1(wi, wh, ax, ay) * _ggx_g1(wo, wh, ax, ay)
            value += spec_trans * fresnel * _ggx_d(wh, ax, ay) * g / (4.0 * wi.z)
        if spec_trans > 0.0 and refraction_ok:
            g = _ggx_g1(wi, wh, tx, ty) * _ggx_g1(wo, wh, tx, ty)
            value += spec_trans * mat.base_color * (1.0 - f) * _ggx_d(wh, tx, ty) * g / (4.0 * wi.z)
        if reflect and spec_trans < 1.0 and diff_trans < 1.0:
            cos_d = wh.dot(wo)
            value += (1.0 - spec_trans) * (1.0 - diff_trans) * _diffuse(mat, wi.z, cos_o, cos_d)
            if mat.sheen > 0.0:
                value += (1.0 - spec_trans) * (1.0 - diff_trans) * _sheen(mat, cos_o, cos_d)
        if refract and spec_trans < 1.0 and diff_trans > 0.0:
            value += (1.0 - spec_trans) * diff_trans * mat.base_color * INV_PI * ti.abs(cos_o)
        p_specular = 0.5 * spec_trans  # each of reflection and transmission
        p_reflect = (1.0 - spec_trans) * (1.0 - diff_trans)
        p_transmit = (1.0 - spec_trans) * diff_trans
        total = 2.0 * p_specular + p_reflect + p_transmit
        dwh_dwo = ti.abs(1.0 / (4.0 * wo_r.dot(wh)))
        if reflection_ok:
            pdf += p_specular * _visible_normal_pdf(wi, wh, ax, ay) * dwh_dwo
        if refraction_ok:
            pdf += p_specular * _visible_normal_pdf(wi, wh, tx, ty) * dwh_dwo
        if reflect:
            pdf += p_reflect * cos_o * INV_PI
        if refract:
            pdf += p_transmit * -cos_o * INV_PI
        pdf /= total
    return value, pdf


@ti.func
def _thin_direction(mat, wi_any, u1, u2):
    """(wo, valid): a direction drawn as Mitsuba's principledthin draws it."""
    spec_trans = mat.transmission
    diff_trans = 0.5 * mat.diff_trans
    cos_i = wi_any.z
    wi = _mulsign(wi_any, cos_i)
    p_specular = 0.5 * spec_trans
    p_reflect = (1.0 - spec_trans) * (1.0 - diff_trans)
    u = u1 * (2.0 * p_specular + p_reflect + (1.0 - spec_trans) * diff_trans)
    wo = vec3(0.0, 0.0, 1.0)
    valid = True
    if u < p_specular:
        ax, ay = _widths(mat.anisotropic, mat.roughness)
        m = mf.sample_visible_normal(wi, ax, u2, ay)
        wo = mf.reflect(wi, m)
        valid = _compatible(m, wi, wo, wi.z, True) and wo.z > 0.0
    elif u < 2.0 * p_specular:
        tx, ty = _widths(mat.anisotropic, (0.65 * mat.ior - 0.35) * mat.roughness)
        m = mf.sample_visible_normal(wi, tx, u2, ty)
        wo = mf.reflect(wi, m)
        wo.z = -wo.z  # the sheet does not bend light: the reflection mirrored through it
        valid = _compatible(m, wi, wo, wi.z, False) and wo.z < 0.0
    elif u < 2.0 * p_specular + p_reflect:
        wo = cosine_hemisphere(u2)
    else:
        wo = -cosine_hemisphere(u2)
    return _mulsign(wo, cos_i), valid


# --- the kind's lobe-module interface -------------------------------------------------------------------
@ti.func
def _evaluate(bsdf, mat, entering, wo, wi):
    """(f |cos wi|, pdf) in Lantern's frame; a row whose back shades as its front is entered from
    either side (Mitsuba's twosided flips both directions to the front)."""
    value = vec3(0.0)
    pdf = 0.0
    thin = False
    if ti.static(bsdf.features.has_thin):
        thin = mat.thin == 1
    if thin:
        if ti.static(bsdf.features.has_thin):
            value, pdf = _thin(mat, wo, wi)
    else:
        front = entering or mat.front_both_sides == 1
        value, pdf = _thick(mat, _mitsuba_frame(wo, front), _mitsuba_frame(wi, front))
    return value, pdf


@ti.func
def evaluate(bsdf, mat, n_f, t, b, entering, wo, wi):
    # Lantern's wo (towards the viewer) is Mitsuba's wi; Lantern's wi is Mitsuba's wo.
    return _evaluate(bsdf, mat, entering, wo, wi)


@ti.func
def sample(bsdf, mat, n_f, t, b, entering, wo, u1, u2):
    s = invalid_sample()
    wi = vec3(0.0)
    valid = False
    thin = False
    if ti.static(bsdf.features.has_thin):
        thin = mat.thin == 1
    if thin:
        if ti.static(bsdf.features.has_thin):
            wi, valid = _thin_direction(mat, wo, u1, u2)
    else:
        front = entering or mat.front_both_sides == 1
        wi_m, valid_m = _thick_direction(mat, _mitsuba_frame(wo, front), u1, u2)
        wi, valid = _mitsuba_frame(wi_m, front), valid_m
    if valid:
        value, pdf = _evaluate(bsdf, mat, entering, wo, wi)
        if pdf > 0.0:
            s = BsdfSample(wi=wi, weight=value / pdf, pdf=pdf, delta=0, valid=1)
    return s


@ti.func
def flags(bsdf, mat):
    f = LobeFlags.REFLECTION | LobeFlags.DIFFUSE | LobeFlags.GLOSSY
    if mat.transmission > 0.0 or (mat.thin == 1 and mat.diff_trans > 0.0):
        f |= LobeFlags.TRANSMISSION
    return f

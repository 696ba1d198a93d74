"""The `coated` kind: pbrt-v4's coateddiffuse and coatedconductor (its LayeredBxDF with a
DielectricBxDF on top and a DiffuseBxDF or ConductorBxDF at the bottom, two-sided).

A dielectric interface of index `ior` (GGX widths alpha, alpha_v; smooth below pbrt's 1e-3) lies
`coat_thickness` above a base (`coat_base`: 0 diffuse of reflectance base_color, 1 conductor of
complex index (eta + i k) / ior and width conductor_alpha). The slab between holds a
Henyey-Greenstein medium of unit extinction, albedo coat_albedo and asymmetry coat_g (none when
the albedo is black: then only its transmittance exp(-thickness / |cos|) acts).

As in pbrt-v4, f and pdf have no closed form: `evaluate` returns Monte Carlo estimates from
coat_nsamples random walks of at most coat_maxdepth bounces, and `sample` draws a walk whose
weight f |cos| / pdf is that walk's own (pbrt's pdfIsProportional). The numbers of a walk come
from a hash of its arguments (wo and wi for f, wi and wo for the pdf, wo and the sample's
numbers for `sample`), so an estimate is a fixed function of its arguments. The pdf that `sample`
reports, for MIS, is the pdf estimate at the sampled direction (the number `evaluate` gives there),
as pbrt's path integrator takes PDF() for a proportional sample; delta samples (a smooth coat's
reflection, a walk through a smooth coat onto a smooth metal) keep the walk's discrete pdf.
pbrt's estimates are kept as they are: with a rough coat, f's exit connection is weighted against
the coat's PDF(-w, wi), a density of wi, so f runs a few percent above what the walk samples.

The walk's interfaces are pbrt's, seen from either side: transport is in radiance mode (the
importance-mode samples of wi's side are pbrt's !mode). Lobe module of kinds.py (see diffuse.py).
"""
import taichi as ti

from renderer.materials import microfacet as mf
from renderer.materials.coat_bases import COAT_BASES
from renderer.materials.kinds import LobeFlags
from renderer.materials.lobes import BsdfSample, invalid_sample
from renderer.media.phase import hg_eval
from renderer.sampling.rng import pcg_hash, uniform
from renderer.sampling.warps import INV_PI, PI, cosine_hemisphere, orthonormal_basis

vec3 = ti.math.vec3
DIFFUSE_BASE, CONDUCTOR_BASE = COAT_BASES["diffuse"], COAT_BASES["conductor"]
SMOOTH_ALPHA = 1e-3  # pbrt's TrowbridgeReitzDistribution::EffectivelySmooth
TOP, BOTTOM = 0, 1
REFLECT, TRANSMIT, ALL = 1, 2, 3  # pbrt's BxDFReflTransFlags
_FLT_MIN = 1.1754944e-38
_INV_4PI = 0.25 * INV_PI

# One interface's sampled scattering: f (not times cos), direction, pdf, and its kind.
Scatter = ti.types.struct(f=vec3, wi=vec3, pdf=ti.f32, reflection=ti.i32, specular=ti.i32, valid=ti.i32)
# The layered BSDF's parameters, read from a Material (params) or set directly by tests.
CoatParams = ti.types.struct(eta=ti.f32, alpha_x=ti.f32, alpha_y=ti.f32, base=ti.i32, reflectance=vec3,
                             c_eta=vec3, c_k=vec3, c_alpha=ti.f32, thickness=ti.f32, albedo=vec3, g=ti.f32,
                             max_depth=ti.i32, n_samples=ti.i32)


@ti.func
def params(mat):
    alpha_v = mat.alpha_v if mat.alpha_v > 0.0 else mat.alpha
    eta = mat.ior if mat.ior != 0.0 else 1.0
    return CoatParams(eta=eta, alpha_x=mat.alpha, alpha_y=alpha_v, base=mat.coat_base, reflectance=mat.base_color,
                      c_eta=mat.eta / eta, c_k=mat.k / eta, c_alpha=mat.conductor_alpha,
                      thickness=ti.max(mat.coat_thickness, _FLT_MIN), albedo=mat.coat_albedo, g=mat.coat_g,
                      max_depth=mat.coat_maxdepth, n_samples=mat.coat_nsamples)


# --- random numbers: a hash of the walk's arguments, then a counter ----------------------------------
@ti.func
def walk_key(a, b):
    k = ti.u32(0x2545F491)
    for i in ti.static(range(3)):
        k = pcg_hash(k ^ ti.bit_cast(a[i], ti.u32))
    for i in ti.static(range(3)):
        k = pcg_hash(k ^ ti.bit_cast(b[i], ti.u32))
    return k


# --- Trowbridge-Reitz as pbrt-v4 has it (height-correlated G, visible normals of either side) -----------
@ti.func
def _tr_pdf(w, wm, ax, ay):
    """pbrt's D(w, wm) = G1(w) / |cos w| D(wm) |w.wm|."""
    return mf.smith_g1(w, ax, ay) / ti.abs(w.z) * mf.ggx_d(wm, ax, ay) * ti.abs(w.dot(wm))


@ti.func
def _tr_sample(w, ax, ay, u):
    """A visible normal of w, or of -w when w is below (the normal always faces up)."""
    v = w if w.z >= 0.0 else -w
    return mf.sample_visible_normal(v, ax, u, ay)


@ti.func
def _fr_dielectric(cos_i, eta):
    f, _, _, _ = mf.fresnel_dielectric_either_side(ti.math.clamp(cos_i, -1.0, 1.0), eta)
    return f


@ti.func
def _refract(wi, n, eta):
    """pbrt's Refract: (valid, wt, etap)."""
    cos_i = n.dot(wi)
    e = eta
    nn = n
    if cos_i < 0.0:
        e = 1.0 / eta
        cos_i = -cos_i
        nn = -n
    sin2_t = ti.max(0.0, 1.0 - cos_i * cos_i) / (e * e)
    valid = sin2_t < 1.0
    cos_t = ti.sqrt(ti.max(0.0, 1.0 - sin2_t))
    return valid, -wi / e + (cos_i / e - cos_t) * nn, e


@ti.func
def _power(f, g):
    f2 = f * f
    return f2 / (f2 + g * g) if f2 + g * g > 0.0 else 0.0


# --- the dielectric top ---------------------------------------------------------------------------------
@ti.func
def _top_smooth(p):
    return p.eta == 1.0 or ti.max(p.alpha_x, p.alpha_y) < SMOOTH_ALPHA


@ti.func
def _top_sample(p, wo, uc, u, radiance, flags):
    """pbrt's DielectricBxDF::Sample_f, from either side; smooth: about the normal, as a delta."""
    s = Scatter(f=vec3(0.0), wi=vec3(0.0, 0.0, 1.0), pdf=0.0, reflection=0, specular=0, valid=0)
    smooth = _top_smooth(p)
    if smooth or wo.z != 0.0:
        wm = vec3(0.0, 0.0, 1.0)
        if not smooth:
            wm = _tr_sample(wo, p.alpha_x, p.alpha_y, u)
        r = _fr_dielectric(wo.dot(wm), p.eta)
        pr = r if (flags & REFLECT) != 0 else 0.0
        pt = 1.0 - r if (flags & TRANSMIT) != 0 else 0.0
        if pr + pt > 0.0:
            if uc < pr / (pr + pt):
                wi = mf.reflect(wo, wm)
                if smooth:
                    s = Scatter(f=vec3(r / ti.abs(wi.z)), wi=wi, pdf=pr / (pr + pt), reflection=1, specular=1, valid=1)
                elif wi.z * wo.z > 0.0:
                    pdf = _tr_pdf(wo, wm, p.alpha_x, p.alpha_y) / (4.0 * ti.abs(wo.dot(wm))) * pr / (pr + pt)
                    f = (mf.ggx_d(wm, p.alpha_x, p.alpha_y) * mf.smith_g2(wo, wi, p.alpha_x, p.alpha_y) * r
                         / (4.0 * wi.z * wo.z))
                    s = Scatter(f=vec3(f), wi=wi, pdf=pdf, reflection=1, specular=0, valid=1)
            else:
                ok, wi, etap = _refract(wo, wm, p.eta)
                if ok and wi.z * wo.z < 0.0 and wi.z != 0.0:
                    ft = (1.0 - r) / ti.abs(wi.z)
                    pdf = pt / (pr + pt)
                    if not smooth:
                        denom = (wi.dot(wm) + wo.dot(wm) / etap) ** 2
                        pdf *= _tr_pdf(wo, wm, p.alpha_x, p.alpha_y) * ti.abs(wi.dot(wm)) / denom
                        ft = ((1.0 - r) * mf.ggx_d(wm, p.alpha_x, p.alpha_y)
                              * mf.smith_g2(wo, wi, p.alpha_x, p.alpha_y)
                              * ti.abs(wi.dot(wm) * wo.dot(wm) / (wi.z * wo.z * denom)))
                    if radiance:
                        ft /= etap * etap
                    s = Scatter(f=vec3(ft), wi=wi, pdf=pdf, reflection=0, specular=1 if smooth else 0, valid=1)
    return s


@ti.func
def _top_half(p, wo, wi):
    """(ok, wm, etap, reflect): pbrt's generalised half vector, facing up, back-facing rejected."""
    reflect = wi.z * wo.z > 0.0
    etap = 1.0
    if not reflect:
        etap = p.eta if wo.z > 0.0 else 1.0 / p.eta
    wm = wi * etap + wo
    ok = wi.z != 0.0 and wo.z != 0.0 and wm.dot(wm) > 0.0
    if ok:
        wm = ti.math.normalize(wm)
        if wm.z < 0.0:
            wm = -wm
        if wm.dot(wi) * wi.z < 0.0 or wm.dot(wo) * wo.z < 0.0:
            ok = False
    return ok, wm, etap, reflect


@ti.func
def _top_f(p, wo, wi, radiance):
    f = 0.0
    if not _top_smooth(p):
        ok, wm, etap, reflect = _top_half(p, wo, wi)
        if ok:
            r = _fr_dielectric(wo.dot(wm), p.eta)
            d = mf.ggx_d(wm, p.alpha_x, p.alpha_y)
            g = mf.smith_g2(wo, wi, p.alpha_x, p.alpha_y)
            if reflect:
                f = d * g * r / ti.abs(4.0 * wi.z * wo.z)
            else:
                denom = (wi.dot(wm) + wo.dot(wm) / etap) ** 2 * wi.z * wo.z
                f = d * (1.0 - r) * g * ti.abs(wi.dot(wm) * wo.dot(wm) / denom)
                if radiance:
                    f /= etap * etap
    return vec3(f)


@ti.func
def _top_pdf(p, wo, wi, flags):
    pdf = 0.0
    if not _top_smooth(p):
        ok, wm, etap, reflect = _top_half(p, wo, wi)
        if ok:
            r = _fr_dielectric(wo.dot(wm), p.eta)
            pr = r if (flags & REFLECT) != 0 else 0.0
            pt = 1.0 - r if (flags & TRANSMIT) != 0 else 0.0
            if pr + pt > 0.0:
                if reflect:
                    pdf = _tr_pdf(wo, wm, p.alpha_x, p.alpha_y) / (4.0 * ti.abs(wo.dot(wm))) * pr / (pr + pt)
                else:
                    denom = (wi.dot(wm) + wo.dot(wm) / etap) ** 2
                    pdf = _tr_pdf(wo, wm, p.alpha_x, p.alpha_y) * ti.abs(wi.dot(wm)) / denom * pt / (pr + pt)
    return pdf


# --- the base: pbrt's DiffuseBxDF or ConductorBxDF (opaque: reflection only) -----------------------------
@ti.func
def _base_smooth(p):
    return p.base == CONDUCTOR_BASE and p.c_alpha < SMOOTH_ALPHA


@ti.func
def _base_sample(p, wo, uc, u, flags):
    s = Scatter(f=vec3(0.0), wi=vec3(0.0, 0.0, 1.0), pdf=0.0, reflection=1, specular=0, valid=0)
    if (flags & REFLECT) != 0:
        if p.base == DIFFUSE_BASE:
            wi = cosine_hemisphere(u)
            if wo.z < 0.0:
                wi.z = -wi.z
            s = Scatter(f=p.reflectance * INV_PI, wi=wi, pdf=ti.abs(wi.z) * INV_PI, reflection=1, specular=0,
                        valid=1)
        elif _base_smooth(p):
            wi = vec3(-wo.x, -wo.y, wo.z)
            c = ti.abs(wi.z)
            s = Scatter(f=mf.fresnel_conductor(c, p.c_eta, p.c_k) / c, wi=wi, pdf=1.0, reflection=1, specular=1,
                        valid=1)
        elif wo.z != 0.0:
            a = p.c_alpha
            wm = _tr_sample(wo, a, a, u)
            wi = mf.reflect(wo, wm)
            if wi.z * wo.z > 0.0:
                pdf = _tr_pdf(wo, wm, a, a) / (4.0 * ti.abs(wo.dot(wm)))
                f = (mf.ggx_d(wm, a) * mf.fresnel_conductor(ti.abs(wo.dot(wm)), p.c_eta, p.c_k)
                     * mf.smith_g2(wo, wi, a) / (4.0 * ti.abs(wi.z) * ti.abs(wo.z)))
                s = Scatter(f=f, wi=wi, pdf=pdf, reflection=1, specular=0, valid=1)
    return s


@ti.func
def _base_f(p, wo, wi):
    f = vec3(0.0)
    if wo.z * wi.z > 0.0:
        if p.base == DIFFUSE_BASE:
            f = p.reflectance * INV_PI
        elif not _base_smooth(p):
            wm = wi + wo
            if wm.dot(wm) > 0.0:
                wm = ti.math.normalize(wm)
                a = p.c_alpha
                f = (mf.ggx_d(wm, a) * mf.fresnel_conductor(ti.abs(wo.dot(wm)), p.c_eta, p.c_k)
                     * mf.smith_g2(wo, wi, a) / (4.0 * ti.abs(wi.z) * ti.abs(wo.z)))
    return f


@ti.func
def _base_pdf(p, wo, wi):
    pdf = 0.0
    if wo.z * wi.z > 0.0:
        if p.base == DIFFUSE_BASE:
            pdf = ti.abs(wi.z) * INV_PI
        elif not _base_smooth(p):
            wm = wo + wi
            if wm.dot(wm) > 0.0:
                wm = ti.math.normalize(wm)
                if wm.z < 0.0:
                    wm = -wm
                pdf = _tr_pdf(wo, wm, p.c_alpha, p.c_alpha) / (4.0 * ti.abs(wo.dot(wm)))
    return pdf


@ti.func
def _iface_sample(p, which, wo, uc, u, radiance, flags):
    s = Scatter(f=vec3(0.0), wi=vec3(0.0, 0.0, 1.0), pdf=0.0, reflection=0, specular=0, valid=0)
    if which == TOP:
        s = _top_sample(p, wo, uc, u, radiance, flags)
    else:
        s = _base_sample(p, wo, uc, u, flags)
    return s


@ti.func
def _usable(s):
    return s.valid == 1 and s.f.max() > 0.0 and s.pdf > 0.0 and s.wi.z != 0.0


# --- the slab: transmittance and the Henyey-Greenstein phase function -------------------------------------
@ti.func
def _tr(dz, w):
    t = 1.0
    if ti.abs(dz) > _FLT_MIN:
        t = ti.exp(-ti.abs(dz / w.z))
    return t


@ti.func
def hg(cos_theta, g):
    """The media's Henyey-Greenstein (renderer/media/phase.py, pbrt's convention) with pbrt's clamp of
    g for layered BSDFs, 0.99."""
    return hg_eval(ti.math.clamp(g, -0.99, 0.99), cos_theta)


@ti.func
def _hg_sample(wo, g, u):
    """pbrt's SampleHenyeyGreenstein: wi about wo, density hg(wo.wi) (g > 0 scatters forward, wi
    near -wo). Not phase.hg_sample: the same density, but pbrt's inversion and azimuth frame, so that
    the walk draws pbrt's directions from the same numbers (tests/materials/coated_reference.py)."""
    gc = ti.math.clamp(g, -0.99, 0.99)
    cos_t = 1.0 - 2.0 * u.x
    if ti.abs(gc) >= 1e-3:
        cos_t = -1.0 / (2.0 * gc) * (1.0 + gc * gc - ((1.0 - gc * gc) / (1.0 + gc - 2.0 * gc * u.x)) ** 2)
    sin_t = ti.sqrt(ti.max(0.0, 1.0 - cos_t * cos_t))
    phi = 2.0 * PI * u.y
    t, b = orthonormal_basis(wo)
    wi = sin_t * ti.cos(phi) * t + sin_t * ti.sin(phi) * b + cos_t * wo
    return wi, hg(cos_t, gc)


@ti.func
def _entrance_pair(p, wo, wi, key, dim):
    """The walk's way in along wo (radiance) and the light's along wi (importance, pbrt's !mode),
    both transmissions through the coat, from one call site (the walks are inlined)."""
    wos = Scatter(f=vec3(0.0), wi=vec3(0.0, 0.0, 1.0), pdf=0.0, reflection=0, specular=0, valid=0)
    wis = wos
    ok = True
    for j in range(2):
        if ok:
            s = _top_sample(p, wo if j == 0 else wi, uniform(key, dim),
                            ti.math.vec2(uniform(key, dim + 1), uniform(key, dim + 2)), j == 0, TRANSMIT)
            dim += 3
            ok = _usable(s)
            if j == 0:
                wos = s
            else:
                wis = s
    return wos, wis, ok, dim


# --- the layered BSDF (wo.z > 0: Lantern's frame is on wo's side, pbrt's two-sided flip done) ---------------
@ti.func
def layered_f(p, wo, wi):
    """pbrt's LayeredBxDF::f estimate (not times cos); reflection only: both bases are opaque."""
    f = vec3(0.0)
    if wi.z > 0.0:
        n = ti.max(p.n_samples, 1)
        f = n * _top_f(p, wo, wi, True)
        key = walk_key(wo, wi)
        dim = 0
        scattering = p.albedo.max() > 0.0
        exit_z = p.thickness
        top_specular = _top_smooth(p)
        base_specular = _base_smooth(p)
        for _ in range(n):
            wos, wis, ok, dim = _entrance_pair(p, wo, wi, key, dim)
            if not ok:
                continue
            beta = wos.f * ti.abs(wos.wi.z) / wos.pdf
            z = p.thickness
            w = wos.wi
            for depth in range(p.max_depth):
                if depth > 3 and beta.max() < 0.25:
                    q = ti.max(0.0, 1.0 - beta.max())
                    u_rr = uniform(key, dim)
                    dim += 1
                    if u_rr < q:
                        break
                    beta /= 1.0 - q
                if not scattering:
                    z = 0.0 if z == p.thickness else p.thickness
                    beta *= _tr(p.thickness, w)
                else:
                    dz = -ti.log(1.0 - uniform(key, dim)) * ti.abs(w.z)
                    dim += 1
                    zp = z + dz if w.z > 0.0 else z - dz
                    if zp == z:
                        continue
                    if 0.0 < zp and zp < p.thickness:
                        wt = 1.0
                        if not top_specular:
                            wt = _power(wis.pdf, hg((-w).dot(-wis.wi), p.g))
                        f += (beta * p.albedo * hg((-w).dot(-wis.wi), p.g) * wt * _tr(zp - exit_z, wis.wi) * wis.f
                              / wis.pdf)
                        w_new, ps_pdf = _hg_sample(-w, p.g, ti.math.vec2(uniform(key, dim), uniform(key, dim + 1)))
                        dim += 2
                        if ps_pdf == 0.0 or w_new.z == 0.0:
                            continue
                        beta *= p.albedo  # p / pdf = 1
                        w = w_new
                        z = zp
                        if ((z < exit_z and w.z > 0.0) or (z > exit_z and w.z < 0.0)) and not top_specular:
                            f_exit = _top_f(p, -w, wi, True)
                            if f_exit.max() > 0.0:
                                exit_pdf = _top_pdf(p, -w, wi, TRANSMIT)
                                f += beta * _tr(zp - exit_z, w_new) * f_exit * _power(ps_pdf, exit_pdf)
                        continue
                    z = ti.math.clamp(zp, 0.0, p.thickness)
                at_exit = z == exit_z
                if not at_exit and not base_specular:
                    wt = 1.0
                    if not top_specular:
                        wt = _power(wis.pdf, _base_pdf(p, -w, -wis.wi))
                    f += (beta * _base_f(p, -w, -wis.wi) * ti.abs(wis.wi.z) * wt * _tr(p.thickness, wis.wi)
                          * wis.f / wis.pdf)
                bs = _iface_sample(p, TOP if at_exit else BOTTOM, -w, uniform(key, dim),
                                   ti.math.vec2(uniform(key, dim + 1), uniform(key, dim + 2)), True, REFLECT)
                dim += 3
                if not _usable(bs):
                    break
                beta *= bs.f * ti.abs(bs.wi.z) / bs.pdf
                w = bs.wi
                if not at_exit:
                    if not top_specular:
                        f_exit = _top_f(p, -w, wi, True)
                        if f_exit.max() > 0.0:
                            wt = 1.0
                            if not base_specular:
                                wt = _power(bs.pdf, _top_pdf(p, -w, wi, TRANSMIT))
                            f += beta * _tr(p.thickness, bs.wi) * f_exit * wt
        f /= n
    return f


@ti.func
def layered_pdf(p, wo, wi):
    """pbrt's LayeredBxDF::PDF estimate, mixed with the uniform sphere's 1 / (4 pi) at 1 : 9."""
    pdf = 0.0
    if wi.z > 0.0:
        n = ti.max(p.n_samples, 1)
        key = walk_key(wi, wo)
        dim = 0
        pdf_sum = n * _top_pdf(p, wo, wi, REFLECT)
        top_specular = _top_smooth(p)
        base_specular = _base_smooth(p)
        for _ in range(n):
            wos, wis, ok, dim = _entrance_pair(p, wo, wi, key, dim)
            if ok:
                if top_specular:
                    pdf_sum += _base_pdf(p, -wos.wi, -wis.wi)
                else:
                    rs = _base_sample(p, -wos.wi, uniform(key, dim),
                                      ti.math.vec2(uniform(key, dim + 1), uniform(key, dim + 2)), ALL)
                    dim += 3
                    if _usable(rs):
                        if base_specular:
                            pdf_sum += _top_pdf(p, -rs.wi, wi, ALL)
                        else:
                            r_pdf = _base_pdf(p, -wos.wi, -wis.wi)
                            pdf_sum += _power(wis.pdf, r_pdf) * r_pdf
                            t_pdf = _top_pdf(p, -rs.wi, wi, ALL)
                            pdf_sum += _power(rs.pdf, t_pdf) * t_pdf
        pdf = 0.1 * _INV_4PI + 0.9 * pdf_sum / n
    return pdf


@ti.func
def layered_sample(p, wo, uc, u):
    """pbrt's LayeredBxDF::Sample_f: (valid, wi, f, pdf, specular path), f not times cos and pdf
    the walk's own (proportional). Step 0 is the entrance at wo with (uc, u); the walk's own
    numbers come from a hash of wo and (uc, u)."""
    out_valid = 0
    out_wi = vec3(0.0, 0.0, 1.0)
    out_f = vec3(0.0)
    out_pdf = 0.0
    out_specular = 0
    key = walk_key(wo, vec3(uc, u.x, u.y))
    dim = 0
    w = vec3(0.0, 0.0, 1.0)
    specular = 1
    f = vec3(1.0)
    pdf = 1.0
    z = p.thickness
    scattering = p.albedo.max() > 0.0
    for step in range(p.max_depth + 1):
        which = TOP
        w_in = wo
        uc_s = uc
        u_s = u
        if step > 0:
            rr_beta = f.max() / pdf
            if step > 4 and rr_beta < 0.25:  # pbrt's depth > 3
                q = ti.max(0.0, 1.0 - rr_beta)
                u_rr = uniform(key, dim)
                dim += 1
                if u_rr < q:
                    break
                pdf *= 1.0 - q
            if w.z == 0.0:
                break
            if scattering:
                dz = -ti.log(1.0 - uniform(key, dim)) * ti.abs(w.z)
                dim += 1
                zp = z + dz if w.z > 0.0 else z - dz
                if zp == z:
                    break
                if 0.0 < zp and zp < p.thickness:
                    w_new, ps_pdf = _hg_sample(-w, p.g, ti.math.vec2(uniform(key, dim), uniform(key, dim + 1)))
                    dim += 2
                    if ps_pdf == 0.0 or w_new.z == 0.0:
                        break
                    f *= p.albedo * ps_pdf
                    pdf *= ps_pdf
                    specular = 0
                    w = w_new
                    z = zp
                    continue
                z = ti.math.clamp(zp, 0.0, p.thickness)
            else:
                z = 0.0 if z == p.thickness else p.thickness
                f *= _tr(p.thickness, w)
            which = BOTTOM if z == 0.0 else TOP
            w_in = -w
            uc_s = uniform(key, dim)
            u_s = ti.math.vec2(uniform(key, dim + 1), uniform(key, dim + 2))
            dim += 3
        s = _iface_sample(p, which, w_in, uc_s, u_s, True, ALL)
        if not _usable(s):
            break
        f *= s.f
        pdf *= s.pdf
        specular = specular & s.specular
        w = s.wi
        if step == 0 and s.reflection == 1:
            out_valid, out_wi, out_f, out_pdf, out_specular = 1, w, f, pdf, specular
            break
        if step > 0 and s.reflection == 0:
            out_valid, out_wi, out_f, out_pdf, out_specular = 1, w, f, pdf, specular
            break
        f *= ti.abs(s.wi.z)
    return out_valid, out_wi, out_f, out_pdf, out_specular


# --- the lobe module --------------------------------------------------------------------------------------
@ti.func
def evaluate(bsdf, mat, n_f, t, b, entering, wo, wi):
    p = params(mat)
    value = vec3(0.0)
    pdf = 0.0
    if wi.z > 0.0:
        value = layered_f(p, wo, wi) * wi.z
        pdf = layered_pdf(p, wo, wi)
    return value, pdf


@ti.func
def sample(bsdf, mat, n_f, t, b, entering, wo, u1, u2):
    p = params(mat)
    return sample_params(p, wo, u1, u2)


@ti.func
def sample_params(p, wo, u1, u2):
    s = invalid_sample()
    valid, wi, f, pdf, specular = layered_sample(p, wo, u1, u2)
    if valid == 1 and wi.z > 0.0:
        weight = f * wi.z / pdf
        if specular == 1:
            s = BsdfSample(wi=wi, weight=weight, pdf=pdf, delta=1, valid=1)
        else:
            s = BsdfSample(wi=wi, weight=weight, pdf=layered_pdf(p, wo, wi), delta=0, valid=1)
    return s


@ti.func
def has_smooth_part(mat):
    """Whether `evaluate` can be non-zero: flags' NON_DELTA bits, for Bsdf.has_smooth_part."""
    p = params(mat)
    return p.base == DIFFUSE_BASE or p.albedo.max() > 0.0 or not (_top_smooth(p) and _base_smooth(p))


@ti.func
def flags(bsdf, mat):
    p = params(mat)
    f = LobeFlags.REFLECTION
    if _top_smooth(p):
        f |= LobeFlags.SPECULAR
    if p.base == DIFFUSE_BASE or p.albedo.max() > 0.0:
        f |= LobeFlags.DIFFUSE
    elif not (_top_smooth(p) and _base_smooth(p)):
        f |= LobeFlags.GLOSSY
    return f

"""The principled material: glTF's metallic-roughness model and its layers.

From the top down (glTF's order):
  clearcoat   KHR_materials_clearcoat: a dielectric layer of index 1.5 with its own roughness and
              normal, weighted by `clearcoat`;
  sheen       KHR_materials_sheen: the Charlie sheen lobe (renderer/materials/sheen.py);
  base        a metal lobe (weight metallic), a transmissive dielectric lobe (weight
              (1 - metallic) transmission: glass, or a thin wall) and an opaque dielectric part
              ((1 - metallic)(1 - transmission)): a specular coat of index `ior`, scaled by
              KHR_materials_specular's strength and colour k, over a diffuse base.

Layers are energy-conserving by albedo scaling, as glTF specifies and OpenPBR does: a layer with
directional albedo A(mu_o) passes 1 - A(mu_o) to what lies below. The clearcoat's albedo is its
rough interface's reflectance R(mu) from the dielectric tables (renderer/materials/
dielectric_energy.py); the sheen's is max(sheen_color) E(mu) (sheen.py). So a white sheen over a
white clearcoat over a white base returns exactly 1, up to the tables' error. Albedo scaling is
not reciprocal: the layered parts are evaluated as light arrives at the viewer (the camera's
direction wo), which is what the path tracers need; photons (SPPM) use the same evaluation.

The diffuse base under the specular coat is layered reciprocally instead (the coat is part of the
same lobe set): base / pi (1 - k R(mu_o)) (1 - k R(mu_i)) / (1 - k Ravg), which integrates to
base (1 - k R(mu_o)) and is symmetric in wo and wi.

Sampling picks one lobe by its estimated albedo at wo and, for non-delta directions, weights the
result by the whole BSDF over the mixture pdf (one-sample MIS over lobes), so `sample` and `eval`
agree. All vectors are local (z = the shading normal on wo's side); mat.coat_normal is local too
(Bsdf converts it).
"""
import taichi as ti

from renderer.spectral.luminance import luminance
from renderer.materials import lobes
from renderer.materials import microfacet as mf
from renderer.materials.kinds import LobeFlags
from renderer.materials.lobes import BsdfSample
from renderer.materials.sheen import sheen_eval
from renderer.sampling.warps import INV_PI, cosine_hemisphere, orthonormal_basis, to_local, to_world

vec3 = ti.math.vec3
COAT_IOR = 1.5  # KHR_materials_clearcoat fixes the coat's index


@ti.func
def specular_weight(bsdf, mat):
    """k: KHR_materials_specular's strength times colour (1 without the extension)."""
    k = vec3(1.0)
    if ti.static(bsdf.features.has_layer("specular")):
        k = ti.math.clamp(mat.specular * mat.specular_color, 0.0, 1.0)
    return k


@ti.func
def _base_albedos(bsdf, mat, wo):
    """Unnormalised albedo estimates of (metal, glass, coat specular, coat diffuse) at wo."""
    f_view, _ = mf.fresnel_dielectric(wo.z, mat.ior)
    k = luminance(specular_weight(bsdf, mat))
    opaque = (1.0 - mat.metallic) * (1.0 - mat.transmission)
    a_metal = mat.metallic * ti.max(luminance(mf.fresnel_schlick(mat.base_color, wo.z)), 0.05)
    a_glass = (1.0 - mat.metallic) * mat.transmission
    a_spec = opaque * f_view * k
    a_diff = opaque * (1.0 - f_view * k) * ti.max(luminance(mat.base_color), 0.05)
    return ti.math.vec4(a_metal, a_glass, a_spec, a_diff)


@ti.func
def _layers(bsdf, mat, wo):
    """At wo: (what reaches the base, what reaches the sheen (the coat lets through), the
    clearcoat's albedo, the sheen's albedo as seen through the coat)."""
    below_coat = 1.0
    coat = 0.0
    sheen = 0.0
    through = 1.0
    if ti.static(bsdf.features.has_layer("clearcoat")):
        if mat.clearcoat > 0.0:
            r, _ = bsdf.dielectric_tables.reflectance(ti.max(wo.dot(mat.coat_normal), 0.0),
                                                      ti.sqrt(mat.clearcoat_alpha), COAT_IOR)
            coat = mat.clearcoat * r
            below_coat = 1.0 - coat
            through = below_coat
    if ti.static(bsdf.features.has_layer("sheen")):
        strength = mat.sheen_color.max()
        if strength > 0.0:
            e = strength * bsdf.sheen_tables.albedo(wo.z, mat.sheen_roughness)
            sheen = below_coat * e
            through = below_coat * (1.0 - e)
    return through, below_coat, coat, sheen


@ti.func
def _probabilities(bsdf, mat, wo):
    """(base lobes' probabilities (metal, glass, specular, diffuse), layers' (coat, sheen), what
    reaches the base, what reaches the sheen): probabilities in proportion to estimated albedos."""
    a = _base_albedos(bsdf, mat, wo)
    through, below_coat, coat, sheen = _layers(bsdf, mat, wo)
    total = through * (a.x + a.y + a.z + a.w) + coat + sheen
    base = ti.math.vec4(0.0, 0.0, 0.0, 1.0)
    layers = ti.math.vec2(0.0)
    if total > 0.0:
        base = through * a / total
        layers = ti.math.vec2(coat, sheen) / total
    return base, layers, through, below_coat


@ti.func
def _coat_frame(mat):
    n = mat.coat_normal
    t, b = orthonormal_basis(n)
    return n, t, b


@ti.func
def _coat_eval(mat, wo, wi):
    """The clearcoat's specular lobe (unweighted by `clearcoat`) in its own normal's frame."""
    value = vec3(0.0)
    pdf = 0.0
    if mat.clearcoat_alpha > 0.0 and wi.z > 0.0:
        n, t, b = _coat_frame(mat)
        wo_c = to_local(wo, t, b, n)
        wi_c = to_local(wi, t, b, n)
        if wo_c.z > 0.0:
            value, pdf = lobes.coat_specular_eval(COAT_IOR, mat.clearcoat_alpha, wo_c, wi_c)
    return value, pdf


@ti.func
def _diffuse_eval(bsdf, mat, k, wo, wi):
    """The diffuse base under the specular coat, layered reciprocally (module docs)."""
    value = vec3(0.0)
    pdf = 0.0
    if wi.z > 0.0:
        roughness = ti.sqrt(mat.alpha)
        r_o, r_avg = bsdf.dielectric_tables.reflectance(wo.z, roughness, mat.ior)
        r_i, _ = bsdf.dielectric_tables.reflectance(wi.z, roughness, mat.ior)
        layered = (1.0 - k * r_o) * (1.0 - k * r_i) / ti.max(1.0 - k * r_avg, 1e-6)
        value = mat.base_color * layered * (wi.z * INV_PI)
        pdf = wi.z * INV_PI
    return value, pdf


@ti.func
def principled_eval(bsdf, mat, entering, wo, wi):
    """f |cos wi| and the pdf with which principled_sample picks wi (non-delta lobes)."""
    p, layer_p, through, below_coat = _probabilities(bsdf, mat, wo)
    k = specular_weight(bsdf, mat)
    opaque = (1.0 - mat.metallic) * (1.0 - mat.transmission)
    value = vec3(0.0)
    pdf = 0.0
    if mat.alpha > 0.0:
        h = ti.math.normalize(wo + wi)
        fresnel_metal = mf.fresnel_schlick(mat.base_color, ti.max(wo.dot(h), 0.0))
        f_metal, pdf_metal = bsdf.metal_eval(fresnel_metal, lobes.schlick_average(mat.base_color), mat.alpha, wo, wi)
        f_glass, pdf_glass = bsdf.glass_eval(mat, entering, wo, wi)
        f_spec, pdf_spec = lobes.coat_specular_eval(mat.ior, mat.alpha, wo, wi)
        value = mat.metallic * f_metal + (1.0 - mat.metallic) * mat.transmission * f_glass + opaque * k * f_spec
        pdf = p.x * pdf_metal + p.y * pdf_glass + p.z * pdf_spec
    f_diff, pdf_diff = _diffuse_eval(bsdf, mat, k, wo, wi)
    value = through * (value + opaque * f_diff)
    pdf += p.w * pdf_diff
    if ti.static(bsdf.features.has_layer("clearcoat")):
        if mat.clearcoat > 0.0:
            f_coat, pdf_coat = _coat_eval(mat, wo, wi)
            value += mat.clearcoat * f_coat
            pdf += layer_p.x * pdf_coat
    if ti.static(bsdf.features.has_layer("sheen")):
        if mat.sheen_color.max() > 0.0:
            f_sheen, pdf_sheen = sheen_eval(mat.sheen_color, mat.sheen_roughness, wo, wi)
            value += below_coat * f_sheen
            pdf += layer_p.y * pdf_sheen
    return value, pdf


@ti.func
def principled_sample(bsdf, mat, entering, wo, u1, u2):
    p, layer_p, through, _ = _probabilities(bsdf, mat, wo)
    k = specular_weight(bsdf, mat)
    opaque = (1.0 - mat.metallic) * (1.0 - mat.transmission)
    s = lobes.invalid_sample()
    mixture = 0  # 1 when a non-delta direction was drawn: it is weighted by the whole mixture
    # Pick a lobe with u1 (layers first, then the base's lobes), then reuse u1's remainder inside
    # the lobe (it stays uniform).
    u = u1 - layer_p.x - layer_p.y
    if u1 < layer_p.x:
        n, t, b = _coat_frame(mat)
        wo_c = to_local(wo, t, b, n)
        if mat.clearcoat_alpha == 0.0:
            wi = to_world(vec3(-wo_c.x, -wo_c.y, wo_c.z), t, b, n)
            if wi.z > 0.0 and wo_c.z > 0.0:
                f, _ = mf.fresnel_dielectric(wo_c.z, COAT_IOR)
                s = BsdfSample(wi=wi, weight=vec3(mat.clearcoat * f / layer_p.x), pdf=layer_p.x, delta=1, valid=1)
        elif wo_c.z > 0.0:
            s.wi = to_world(lobes.ggx_reflection_direction(mat.clearcoat_alpha, wo_c, u2), t, b, n)
            mixture = 1 if s.wi.z > 0.0 else 0
    elif u1 < layer_p.x + layer_p.y:
        s.wi = cosine_hemisphere(u2)
        mixture = 1
    elif u < p.x:
        if mat.alpha == 0.0:
            f = mf.fresnel_schlick(mat.base_color, wo.z)
            s = BsdfSample(wi=vec3(-wo.x, -wo.y, wo.z), weight=f * (through * mat.metallic / p.x), pdf=p.x,
                           delta=1, valid=1)
        else:
            s.wi = bsdf.metal_direction(mat.alpha, wo, u / p.x, u2)
            if s.wi.z > 0.0:  # a reflection below the surface is a failed sample, as in conductor_sample
                mixture = 1
    elif u < p.x + p.y:
        u_glass = (u - p.x) / p.y
        if mat.alpha == 0.0:
            s = bsdf.glass_sample(mat, entering, wo, u_glass, u2)
            s.weight *= through * (1.0 - mat.metallic) * mat.transmission / p.y
            s.pdf *= p.y
        else:
            wi, valid = bsdf.glass_direction(mat, entering, wo, u_glass, u2)
            s.wi = wi
            mixture = valid
    elif u < p.x + p.y + p.z:
        if mat.alpha == 0.0:
            f_view, _ = mf.fresnel_dielectric(wo.z, mat.ior)
            s = BsdfSample(wi=vec3(-wo.x, -wo.y, wo.z), weight=k * (through * opaque * f_view / p.z), pdf=p.z,
                           delta=1, valid=1)
        else:
            s.wi = lobes.ggx_reflection_direction(mat.alpha, wo, u2)
            if s.wi.z > 0.0:
                mixture = 1
    else:
        s.wi = cosine_hemisphere(u2)
        mixture = 1
    if mixture == 1:
        value, pdf = principled_eval(bsdf, mat, entering, wo, s.wi)
        if pdf > 0.0 and s.wi.z != 0.0:
            s = BsdfSample(wi=s.wi, weight=value / pdf, pdf=pdf, delta=0, valid=1)
    return s


@ti.func
def principled_has_smooth_part(bsdf, mat):
    """Whether eval can be non-zero: a rough lobe, the diffuse base, a rough coat or a sheen."""
    smooth = mat.alpha > 0.0 or (mat.metallic < 1.0 and mat.transmission < 1.0)
    if ti.static(bsdf.features.has_layer("clearcoat")):
        smooth = smooth or (mat.clearcoat > 0.0 and mat.clearcoat_alpha > 0.0)
    if ti.static(bsdf.features.has_layer("sheen")):
        smooth = smooth or mat.sheen_color.max() > 0.0
    return smooth


# --- the kind's lobe module interface (renderer/materials/kinds.py; see diffuse.py) ---------------
@ti.func
def sample(bsdf, mat, n_f, t, b, entering, wo, u1, u2):
    mat.coat_normal = bsdf.local_coat_normal(mat, t, b, n_f)
    return principled_sample(bsdf, mat, entering, wo, u1, u2)


@ti.func
def evaluate(bsdf, mat, n_f, t, b, entering, wo, wi):
    mat.coat_normal = bsdf.local_coat_normal(mat, t, b, n_f)
    return principled_eval(bsdf, mat, entering, wo, wi)


@ti.func
def flags(bsdf, mat):
    """A diffuse base where not all metal or glass; glossy where rough, or a rough coat or a
    sheen; specular where smooth, or a smooth coat."""
    f = LobeFlags.REFLECTION | (LobeFlags.GLOSSY if mat.alpha > 0.0 else LobeFlags.SPECULAR)
    if mat.metallic < 1.0 and mat.transmission < 1.0:
        f |= LobeFlags.DIFFUSE
    if mat.metallic < 1.0 and mat.transmission > 0.0:
        f |= LobeFlags.TRANSMISSION
    if ti.static(bsdf.features.has_layer("clearcoat")):
        if mat.clearcoat > 0.0:
            f |= LobeFlags.GLOSSY if mat.clearcoat_alpha > 0.0 else LobeFlags.SPECULAR
    if ti.static(bsdf.features.has_layer("sheen")):
        if mat.sheen_color.max() > 0.0:
            f |= LobeFlags.GLOSSY
    return f

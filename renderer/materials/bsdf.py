"""The BSDF of every material kind, over the device material table.

Kinds: null (an invisible boundary, e.g. of a medium), diffuse (Lambert), conductor (GGX; Fresnel from the colour at normal incidence and an edge
tint, or exact from a complex index of refraction eta + i k), dielectric (smooth or rough glass) and principled (glTF metallic-roughness: a metal lobe, a
transmissive dielectric lobe and a dielectric coat over a diffuse base, weighted by metallic and
transmission, with base-colour, metallic-roughness, normal, emissive and transmission textures).

Only the kinds and texture slots `Features` calls for are compiled in (`ti.static`). Roughness 0 is
an exact delta lobe, never a tiny GGX.

World-space API (n: the outward shading normal; wo: towards where the path came from):
  shade(surface, wo) -> (Material, n_shading)   textures and normal map applied
  sample(mat, n, wo, u1, u2) -> BsdfSample      weight = f |cos| / pdf, pdf of the whole technique
  eval(mat, n, wo, wi) -> (f |cos|, pdf)        non-delta parts; pdf as `sample` would give wi
The principled model samples one lobe chosen by its estimated albedo and weights the result by
the whole BSDF over the mixture pdf (one-sample MIS over lobes), so `sample` and `eval` agree.

With `features.energy_compensation`, rough GGX reflection of conductors and of the principled
metal lobe adds Kulla and Conty's multiple-scattering lobe (renderer/materials/energy.py), so
rough metals no longer darken with roughness; rough dielectric interfaces (glass, the principled
glass lobe) add the lobe of renderer/materials/dielectric_energy.py, so a white rough glass solid
keeps all its light; and the principled model's diffuse base is layered under its coat so that
the coat's reflection and the base's share add up to one for a white base.
"""
import taichi as ti

from renderer.geometry.shading import consistent_shading_normal
from renderer.materials import lobes
from renderer.materials import microfacet as mf
from renderer.materials.lobes import BsdfSample
from renderer.materials.table import (CONDUCTOR, DIELECTRIC, DIFFUSE, NO_TEXTURE, NULL, PRINCIPLED, Material,
                                      alpha_of)
from renderer.sampling.warps import INV_PI, cosine_hemisphere, orthonormal_basis, to_local, to_world

vec3 = ti.math.vec3


@ti.func
def luminance(c):
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z


@ti.data_oriented
class Bsdf:
    """The BSDF over a material table, with only the lobes and textures `features` calls for."""

    def __init__(self, materials, features):
        self.materials = materials
        self.features = features
        # Energy compensation is a compile-time switch; the albedo table exists only with it.
        self.compensate = features.energy_compensation
        self.energy = materials.ggx_albedo if self.compensate else None
        # Rough glass and the principled model's dielectric parts (glass lobe, coat layering).
        self.compensate_glass = self.compensate and (features.has_dielectric or features.has_principled)
        self.glass_energy = materials.dielectric_albedo if self.compensate_glass else None

    @ti.func
    def shade(self, surface, wo):
        """The material at a surface point (textures and vertex colours applied) and the shading
        normal to use."""
        rec = self.materials.table[surface.material]
        n = surface.n_shading
        mat = Material(kind=rec.kind, base_color=rec.base_color, alpha=alpha_of(rec.roughness), metallic=rec.metallic,
                       transmission=rec.transmission, ior=rec.ior, emission=rec.emission, edge_tint=rec.edge_tint,
                       complex_ior=rec.complex_ior, eta=rec.eta, k=rec.k, fresnel_avg=rec.fresnel_avg, thin=rec.thin,
                       clearcoat=rec.clearcoat, clearcoat_alpha=alpha_of(rec.clearcoat_roughness),
                       sheen_color=rec.sheen_color, sheen_roughness=rec.sheen_roughness, specular=rec.specular,
                       specular_color=rec.specular_color, coat_normal=n)
        if ti.static(self.features.has_vertex_colors):
            mat.base_color *= surface.color.xyz
        if ti.static(self.features.has_textures):
            tex = self.materials.textures
            if rec.textures[0] != NO_TEXTURE:
                mat.base_color *= tex.sample(rec.textures[0], surface.uv, surface.uv1).xyz
            if rec.textures[1] != NO_TEXTURE:
                mr = tex.sample(rec.textures[1], surface.uv, surface.uv1)
                mat.alpha = alpha_of(rec.roughness * mr.y)
                mat.metallic = rec.metallic * mr.z
            if rec.textures[3] != NO_TEXTURE:
                mat.emission *= tex.sample(rec.textures[3], surface.uv, surface.uv1).xyz
            if rec.transmission_texture != NO_TEXTURE:
                mat.transmission *= tex.sample(rec.transmission_texture, surface.uv, surface.uv1).x
            if ti.static(self.features.has_clearcoat):
                if rec.layer_textures[0] != NO_TEXTURE:
                    mat.clearcoat *= tex.sample(rec.layer_textures[0], surface.uv, surface.uv1).x
                if rec.layer_textures[1] != NO_TEXTURE:
                    mat.clearcoat_alpha = alpha_of(rec.clearcoat_roughness
                                                   * tex.sample(rec.layer_textures[1], surface.uv, surface.uv1).y)
            if ti.static(self.features.has_sheen):
                if rec.layer_textures[2] != NO_TEXTURE:
                    mat.sheen_color *= tex.sample(rec.layer_textures[2], surface.uv, surface.uv1).xyz
                if rec.layer_textures[3] != NO_TEXTURE:
                    mat.sheen_roughness *= tex.sample(rec.layer_textures[3], surface.uv, surface.uv1).w
            if ti.static(self.features.has_specular):
                if rec.layer_textures2[0] != NO_TEXTURE:
                    mat.specular *= tex.sample(rec.layer_textures2[0], surface.uv, surface.uv1).w
                if rec.layer_textures2[1] != NO_TEXTURE:
                    mat.specular_color *= tex.sample(rec.layer_textures2[1], surface.uv, surface.uv1).xyz
            if ti.static(self.features.has_normal_maps):
                if rec.textures[2] != NO_TEXTURE:
                    n = _normal_mapped(tex, rec.textures[2], rec.normal_scale, surface, n, wo)
                mat.coat_normal = n
                if ti.static(self.features.has_clearcoat):
                    if rec.layer_textures2[2] != NO_TEXTURE:
                        mat.coat_normal = _normal_mapped(tex, rec.layer_textures2[2], rec.clearcoat_normal_scale,
                                                         surface, surface.n_shading, wo)
        return mat, n

    @ti.func
    def _frame(self, n, wo_world):
        n_f = n if n.dot(wo_world) >= 0.0 else -n  # the side wo is on
        t, b = orthonormal_basis(n_f)
        return n_f, t, b

    @ti.func
    def sample(self, mat, n, wo_world, u1, u2):
        """Sample wi given wo; u1 picks a lobe, u2 the direction within it."""
        n_f, t, b = self._frame(n, wo_world)
        wo = to_local(wo_world, t, b, n_f)
        entering = n.dot(wo_world) >= 0.0
        s = lobes.invalid_sample()
        if wo.z > 0.0:
            if ti.static(self.features.has_diffuse):
                if mat.kind == DIFFUSE:
                    s = lobes.diffuse_sample(mat.base_color, wo, u2)
            if ti.static(self.features.has_conductor):
                if mat.kind == CONDUCTOR:
                    if ti.static(not self.compensate):
                        s = lobes.conductor_sample(mat, wo, u2)
                    else:
                        s = _compensated_conductor_sample(self.energy, mat, wo, u1, u2)
            if ti.static(self.features.has_dielectric):
                if mat.kind == DIELECTRIC:
                    s = self._dielectric_sample(mat.base_color, mat.alpha, _eta(mat, entering), wo, u1, u2)
            if ti.static(self.features.has_principled):
                if mat.kind == PRINCIPLED:
                    s = _principled_sample(self, mat, entering, wo, u1, u2)
            if ti.static(self.features.has_null):
                if mat.kind == NULL:  # an invisible boundary: straight on, nothing changes
                    s = BsdfSample(wi=-wo, weight=vec3(1.0), pdf=1.0, delta=1, valid=1)
        if s.valid == 1 and not _finite_positive(s.weight):
            s.valid = 0  # a numerically broken sample ends the path rather than reaching the film
        s.wi = to_world(s.wi, t, b, n_f)
        return s

    @ti.func
    def eval(self, mat, n, wo_world, wi_world):
        """f * |cos(wi)| and the pdf with which `sample` picks wi (non-delta lobes only)."""
        n_f, t, b = self._frame(n, wo_world)
        wo = to_local(wo_world, t, b, n_f)
        wi = to_local(wi_world, t, b, n_f)
        entering = n.dot(wo_world) >= 0.0
        value = vec3(0.0)
        pdf = 0.0
        if wo.z > 0.0:
            if ti.static(self.features.has_diffuse):
                if mat.kind == DIFFUSE:
                    value, pdf = lobes.diffuse_eval(mat.base_color, wo, wi)
            if ti.static(self.features.has_conductor):
                if mat.kind == CONDUCTOR:
                    if ti.static(not self.compensate):
                        value, pdf = lobes.conductor_eval(mat, wo, wi)
                    else:
                        value, pdf = _compensated_conductor_eval(self.energy, mat, wo, wi)
            if ti.static(self.features.has_dielectric):
                if mat.kind == DIELECTRIC:
                    value, pdf = self._dielectric_eval(mat.base_color, mat.alpha, _eta(mat, entering), wo, wi)
            if ti.static(self.features.has_principled):
                if mat.kind == PRINCIPLED:
                    value, pdf = _principled_eval(self, mat, entering, wo, wi)
        return value, pdf

    # --- the dielectric interface, with multiple scattering where compensation is on ----------------
    @ti.func
    def _dielectric_sample(self, tint, alpha, eta, wo, u1, u2):
        s = lobes.invalid_sample()
        if ti.static(self.compensate_glass):
            if alpha > 0.0:
                s = self.glass_energy.sample(tint, alpha, eta, wo, u1, u2)
            else:
                s = lobes.dielectric_sample(tint, alpha, eta, wo, u1, u2)
        else:
            s = lobes.dielectric_sample(tint, alpha, eta, wo, u1, u2)
        return s

    @ti.func
    def _dielectric_eval(self, tint, alpha, eta, wo, wi):
        value = vec3(0.0)
        pdf = 0.0
        if ti.static(self.compensate_glass):
            if alpha > 0.0:
                value, pdf = self.glass_energy.eval(tint, alpha, eta, wo, wi)
        else:
            value, pdf = lobes.dielectric_eval(tint, alpha, eta, wo, wi)
        return value, pdf

    @ti.func
    def sample_at(self, mat, n, ng, wo, u1, u2):
        """`sample` at a surface with geometric normal ng: a direction that the shading normal
        calls reflection but the true surface calls transmission (or the reverse) would cross the
        surface the wrong way, so it ends the path (pbrt's rule; without it light leaks through
        smooth-shaded meshes)."""
        s = self.sample(mat, n, wo, u1, u2)
        if s.valid == 1 and not _sides_agree(n, ng, wo, s.wi):
            s.valid = 0
        return s

    @ti.func
    def eval_at(self, mat, n, ng, wo, wi):
        """`eval` at a surface with geometric normal ng (see sample_at)."""
        value, pdf = self.eval(mat, n, wo, wi)
        if not _sides_agree(n, ng, wo, wi):
            value = vec3(0.0)
        return value, pdf

    @ti.func
    def has_smooth_part(self, mat):
        """Whether eval can be non-zero (light sampling is pointless on a purely delta BSDF)."""
        smooth = mat.alpha > 0.0
        if mat.kind == DIFFUSE:
            smooth = True
        elif mat.kind == NULL:
            smooth = False
        elif mat.kind == PRINCIPLED:
            smooth = smooth or (mat.metallic < 1.0 and mat.transmission < 1.0)
        return smooth

    @ti.func
    def albedo(self, mat):
        """A display albedo for the debug view (not an integral of the BSDF)."""
        return mat.base_color


@ti.func
def _normal_mapped(tex, slot, scale, surface, n, wo):
    """The shading normal a tangent-space normal map gives at the surface (n where the surface
    has no tangents or the map's normal degenerates)."""
    result = n
    if surface.tangent.xyz.dot(surface.tangent.xyz) > 0.0:
        texel = tex.sample(slot, surface.uv, surface.uv1).xyz * 2.0 - 1.0
        t = surface.tangent.xyz
        b = surface.tangent.w * n.cross(t)
        mapped = t * (texel.x * scale) + b * (texel.y * scale) + n * texel.z
        if mapped.dot(mapped) > 1e-12:
            result = consistent_shading_normal(ti.math.normalize(mapped), surface.n_geo, wo)
    return result


@ti.func
def _sides_agree(n, ng, wo, wi):
    shading_reflects = wi.dot(n) * wo.dot(n) > 0.0
    geometry_reflects = wi.dot(ng) * wo.dot(ng) > 0.0
    return shading_reflects == geometry_reflects


@ti.func
def _eta(mat, entering):
    return mat.ior if entering else 1.0 / mat.ior


@ti.func
def _finite_positive(v):
    # Bit-level test: Taichi's fast math folds `x != x`. An all-ones exponent is inf or NaN.
    ok = True
    for i in ti.static(range(3)):
        bits = ti.bit_cast(v[i], ti.i32)
        if (bits & 0x7F800000) == 0x7F800000 or v[i] < 0.0:
            ok = False
    return ok


# --- GGX reflection with multiple scattering (Kulla-Conty) ------------------------------------------------
@ti.func
def _compensated_reflection_eval(energy, fresnel_h, f_avg, alpha, wo, wi):
    """Single scattering (Fresnel fresnel_h at the half vector) plus the multiple-scattering lobe;
    the pdf of _compensated_reflection_direction."""
    v_ss, pdf_ss = lobes.ggx_reflection_eval(fresnel_h, alpha, wo, wi)
    v_ms, pdf_ms, share = energy.multiple_scattering(f_avg, alpha, wo, wi)
    return v_ss + v_ms, (1.0 - share) * pdf_ss + share * pdf_ms


@ti.func
def _compensated_reflection_direction(energy, alpha, wo, u_choice, u2):
    wi = vec3(0.0)
    if u_choice < energy.sampling_share(alpha, wo):
        wi = cosine_hemisphere(u2)
    else:
        wi = lobes.ggx_reflection_direction(alpha, wo, u2)
    return wi


@ti.func
def _compensated_conductor_eval(energy, mat, wo, wi):
    h = ti.math.normalize(wo + wi)
    fresnel = lobes.conductor_reflectance(mat, wo.dot(h))
    return _compensated_reflection_eval(energy, fresnel, lobes.conductor_reflectance_average(mat),
                                        mat.alpha, wo, wi)


@ti.func
def _compensated_conductor_sample(energy, mat, wo, u1, u2):
    s = lobes.invalid_sample()
    if mat.alpha == 0.0:  # a smooth mirror scatters once: nothing to compensate
        s = lobes.conductor_sample(mat, wo, u2)
    else:
        wi = _compensated_reflection_direction(energy, mat.alpha, wo, u1, u2)
        if wi.z > 0.0:
            value, pdf = _compensated_conductor_eval(energy, mat, wo, wi)
            if pdf > 0.0:
                s = BsdfSample(wi=wi, weight=value / pdf, pdf=pdf, delta=0, valid=1)
    return s


# --- principled ---------------------------------------------------------------------------------------
@ti.func
def _principled_lobe_probabilities(mat, wo):
    """Probabilities of (metal, glass, coat specular, coat diffuse), from each lobe's estimated
    albedo at wo: the lobes that return the most light get the most samples."""
    f_view, _ = mf.fresnel_dielectric(wo.z, mat.ior)
    opaque = (1.0 - mat.metallic) * (1.0 - mat.transmission)
    a_metal = mat.metallic * ti.max(luminance(mf.fresnel_schlick(mat.base_color, wo.z)), 0.05)
    a_glass = (1.0 - mat.metallic) * mat.transmission
    a_spec = opaque * f_view
    a_diff = opaque * (1.0 - f_view) * ti.max(luminance(mat.base_color), 0.05)
    total = a_metal + a_glass + a_spec + a_diff
    p = ti.math.vec4(0.0, 0.0, 0.0, 1.0)
    if total > 0.0:
        p = ti.math.vec4(a_metal, a_glass, a_spec, a_diff) / total
    return p


@ti.func
def _principled_eval(bsdf, mat, entering, wo, wi):
    p = _principled_lobe_probabilities(mat, wo)
    opaque = (1.0 - mat.metallic) * (1.0 - mat.transmission)
    value = vec3(0.0)
    pdf = 0.0
    if mat.alpha > 0.0:
        h = ti.math.normalize(wo + wi)
        f_metal = vec3(0.0)
        pdf_metal = 0.0
        fresnel_metal = mf.fresnel_schlick(mat.base_color, ti.max(wo.dot(h), 0.0))
        if ti.static(not bsdf.compensate):
            f_metal, pdf_metal = lobes.ggx_reflection_eval(fresnel_metal, mat.alpha, wo, wi)
        else:
            f_metal, pdf_metal = _compensated_reflection_eval(bsdf.energy, fresnel_metal,
                                                              lobes.schlick_average(mat.base_color), mat.alpha, wo, wi)
        f_glass, pdf_glass = bsdf._dielectric_eval(mat.base_color, mat.alpha, _eta(mat, entering), wo, wi)
        f_spec, pdf_spec = lobes.coat_specular_eval(mat.ior, mat.alpha, wo, wi)
        value = mat.metallic * f_metal + (1.0 - mat.metallic) * mat.transmission * f_glass + opaque * f_spec
        pdf = p.x * pdf_metal + p.y * pdf_glass + p.z * pdf_spec
    f_diff, pdf_diff = _coat_diffuse_eval(bsdf, mat, wo, wi)
    value += opaque * f_diff
    pdf += p.w * pdf_diff
    return value, pdf


@ti.func
def _coat_diffuse_eval(bsdf, mat, wo, wi):
    """The diffuse base under the dielectric coat. With compensation, an energy-conserving layering:
    what the rough coat does not reflect (R_o from the dielectric table, the albedo of the coat's
    own specular lobe) reaches the base on the way in and out,
        base / pi (1 - R_o(mu_o)) (1 - R_o(mu_i)) / (1 - Ravg_o),
    which is reciprocal and integrates to base (1 - R_o(mu_o)): a white base under a clear coat
    returns everything the coat lets through. Without it, the smooth-Fresnel form of
    lobes.coat_diffuse_eval (which loses the light the coat reflects back down)."""
    value = vec3(0.0)
    pdf = 0.0
    if ti.static(bsdf.compensate_glass):
        if wi.z > 0.0:
            roughness = ti.sqrt(mat.alpha)
            r_o, r_avg = bsdf.glass_energy.reflectance(wo.z, roughness, mat.ior)
            r_i, _ = bsdf.glass_energy.reflectance(wi.z, roughness, mat.ior)
            value = mat.base_color * ((1.0 - r_o) * (1.0 - r_i) / ti.max(1.0 - r_avg, 1e-6) * wi.z * INV_PI)
            pdf = wi.z * INV_PI
    else:
        value, pdf = lobes.coat_diffuse_eval(mat.base_color, mat.ior, wo, wi)
    return value, pdf


@ti.func
def _principled_sample(bsdf, mat, entering, wo, u1, u2):
    p = _principled_lobe_probabilities(mat, wo)
    opaque = (1.0 - mat.metallic) * (1.0 - mat.transmission)
    s = lobes.invalid_sample()
    mixture = 0  # 1 when a non-delta direction was drawn: it is weighted by the whole mixture
    # Pick a lobe with u1, then reuse u1's remainder inside the lobe (it stays uniform).
    if u1 < p.x:
        if mat.alpha == 0.0:
            f = mf.fresnel_schlick(mat.base_color, wo.z)
            s = BsdfSample(wi=vec3(-wo.x, -wo.y, wo.z), weight=f * (mat.metallic / p.x), pdf=p.x, delta=1, valid=1)
        else:
            if ti.static(not bsdf.compensate):
                s.wi = lobes.ggx_reflection_direction(mat.alpha, wo, u2)
            else:
                s.wi = _compensated_reflection_direction(bsdf.energy, mat.alpha, wo, u1 / p.x, u2)
            if s.wi.z > 0.0:  # a reflection below the surface is a failed sample, as in conductor_sample
                mixture = 1
    elif u1 < p.x + p.y:
        u_glass = (u1 - p.x) / p.y
        if mat.alpha == 0.0:
            s = lobes.dielectric_sample(mat.base_color, mat.alpha, _eta(mat, entering), wo, u_glass, u2)
            s.weight *= (1.0 - mat.metallic) * mat.transmission / p.y
            s.pdf *= p.y
        else:
            wi = vec3(0.0, 0.0, 1.0)
            valid = 0
            if ti.static(bsdf.compensate_glass):
                wi, valid = bsdf.glass_energy.direction(mat.base_color, mat.alpha, _eta(mat, entering), wo,
                                                        u_glass, u2)
            else:
                g = lobes.dielectric_sample(mat.base_color, mat.alpha, _eta(mat, entering), wo, u_glass, u2)
                wi = g.wi
                valid = g.valid
            s.wi = wi
            mixture = valid
    elif u1 < p.x + p.y + p.z:
        if mat.alpha == 0.0:
            f_view, _ = mf.fresnel_dielectric(wo.z, mat.ior)
            s = BsdfSample(wi=vec3(-wo.x, -wo.y, wo.z), weight=vec3(opaque * f_view / p.z), pdf=p.z, delta=1, valid=1)
        else:
            s.wi = lobes.ggx_reflection_direction(mat.alpha, wo, u2)
            if s.wi.z > 0.0:  # a reflection below the surface is a failed sample, as in conductor_sample
                mixture = 1
    else:
        s.wi = lobes.diffuse_sample(mat.base_color, wo, u2).wi
        mixture = 1
    if mixture == 1:
        value, pdf = _principled_eval(bsdf, mat, entering, wo, s.wi)
        if pdf > 0.0 and s.wi.z != 0.0:
            s = BsdfSample(wi=s.wi, weight=value / pdf, pdf=pdf, delta=0, valid=1)
    return s

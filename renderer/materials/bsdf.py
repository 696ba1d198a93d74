"""The BSDF of every material kind, over the device material table.

Kinds: null (an invisible boundary, e.g. of a medium), diffuse (Lambert), conductor (GGX; Fresnel
from the colour at normal incidence and an edge tint, or exact from a complex index of refraction
eta + i k), dielectric (smooth or rough glass; `thin`: a thin wall that reflects or lets light
straight through) and principled (glTF metallic-roughness with its clearcoat, sheen and specular
layers: renderer/materials/principled.py).

Only the kinds, layers and texture slots `Features` calls for are compiled in (`ti.static`).
Roughness 0 is an exact delta lobe, never a tiny GGX.

World-space API (n: the outward shading normal; wo: towards where the path came from):
  shade(surface, wo) -> (Material, n_shading)   textures, vertex colours and normal maps applied
  sample(mat, n, wo, u1, u2) -> BsdfSample      weight = f |cos| / pdf, pdf of the whole technique
  eval(mat, n, wo, wi) -> (f |cos|, pdf)        non-delta parts; pdf as `sample` would give wi

With `features.energy_compensation`, rough GGX reflection of conductors and of the principled
metal lobe adds Kulla and Conty's multiple-scattering lobe (renderer/materials/energy.py), so
rough metals no longer darken with roughness; rough dielectric interfaces (glass, the principled
glass lobe) add the lobe of renderer/materials/dielectric_energy.py, and rough thin walls the
GGX one, so white rough glass keeps all its light.
"""
import taichi as ti

from renderer.geometry.shading import consistent_shading_normal
from renderer.materials import lobes
from renderer.materials.lobes import BsdfSample
from renderer.materials.principled import principled_eval, principled_has_smooth_part, principled_sample
from renderer.materials.table import (CONDUCTOR, DIELECTRIC, DIFFUSE, NO_TEXTURE, NULL, PRINCIPLED, Material,
                                      alpha_of)
from renderer.sampling.warps import cosine_hemisphere, orthonormal_basis, to_local, to_world

vec3 = ti.math.vec3


@ti.data_oriented
class Bsdf:
    """The BSDF over a material table, with only the lobes and textures `features` calls for."""

    def __init__(self, materials, features):
        self.materials = materials
        self.features = features
        # Energy compensation is a compile-time switch; the albedo tables exist only where used.
        self.compensate = features.energy_compensation
        self.energy = materials.ggx_albedo if self.compensate else None
        # Rough glass (and the principled glass lobe) with its multiple-scattering lobe; the
        # principled model's layering reads the same dielectric tables, compensated or not.
        self.compensate_glass = self.compensate and (features.has_dielectric or features.has_principled)
        self.dielectric_tables = (materials.dielectric_albedo if self.compensate_glass or features.has_principled
                                  else None)
        self.sheen_tables = materials.sheen_albedo if features.has_sheen else None

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
                    s = self.glass_sample(mat, entering, wo, u1, u2)
            if ti.static(self.features.has_principled):
                if mat.kind == PRINCIPLED:
                    mat.coat_normal = self._local_coat_normal(mat, t, b, n_f)
                    s = principled_sample(self, mat, entering, wo, u1, u2)
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
                    value, pdf = self.glass_eval(mat, entering, wo, wi)
            if ti.static(self.features.has_principled):
                if mat.kind == PRINCIPLED:
                    mat.coat_normal = self._local_coat_normal(mat, t, b, n_f)
                    value, pdf = principled_eval(self, mat, entering, wo, wi)
        return value, pdf

    # --- glass: thick (refracting) or thin-walled, with multiple scattering where compensation is on ---
    @ti.func
    def glass_sample(self, mat, entering, wo, u1, u2):
        """The dielectric (or the principled glass lobe) with tint mat.base_color."""
        s = lobes.invalid_sample()
        thin = False
        if ti.static(self.features.has_thin):
            thin = mat.thin == 1
        if thin:
            if ti.static(self.features.has_thin):
                s = self._thin_sample(mat, wo, u1, u2)
        elif ti.static(self.compensate_glass):
            if mat.alpha > 0.0:
                s = self.dielectric_tables.sample(mat.base_color, mat.alpha, _eta(mat, entering), wo, u1, u2)
            else:
                s = lobes.dielectric_sample(mat.base_color, mat.alpha, _eta(mat, entering), wo, u1, u2)
        else:
            s = lobes.dielectric_sample(mat.base_color, mat.alpha, _eta(mat, entering), wo, u1, u2)
        return s

    @ti.func
    def glass_eval(self, mat, entering, wo, wi):
        value = vec3(0.0)
        pdf = 0.0
        thin = False
        if ti.static(self.features.has_thin):
            thin = mat.thin == 1
        if thin:
            if ti.static(self.features.has_thin):
                value, pdf = self._thin_eval(mat, wo, wi)
        elif ti.static(self.compensate_glass):
            if mat.alpha > 0.0:
                value, pdf = self.dielectric_tables.eval(mat.base_color, mat.alpha, _eta(mat, entering), wo, wi)
        else:
            value, pdf = lobes.dielectric_eval(mat.base_color, mat.alpha, _eta(mat, entering), wo, wi)
        return value, pdf

    @ti.func
    def glass_direction(self, mat, entering, wo, u1, u2):
        """(wi, valid): a direction as glass_sample draws it, for the principled mixture."""
        s = self.glass_sample(mat, entering, wo, u1, u2)
        return s.wi, s.valid

    @ti.func
    def _thin_sample(self, mat, wo, u1, u2):
        s = lobes.invalid_sample()
        if ti.static(self.compensate):
            if mat.alpha > 0.0:
                # u1 picks the multiple-scattering lobe with its energy share, then (its
                # remainder) reflection or transmission within the chosen lobe.
                wi = vec3(0.0)
                valid = 1
                share = self.energy.sampling_share(mat.alpha, wo)
                if u1 < share:
                    wi = cosine_hemisphere(u2)
                    if u1 / share >= self._thin_reflect_share(mat):
                        wi.z = -wi.z
                else:
                    single = lobes.thin_dielectric_sample(mat.base_color, mat.alpha, mat.ior, wo,
                                                          (u1 - share) / (1.0 - share), u2)
                    wi = single.wi
                    valid = single.valid
                if valid == 1:
                    value, pdf = self._thin_eval(mat, wo, wi)
                    if pdf > 0.0:
                        s = BsdfSample(wi=wi, weight=value / pdf, pdf=pdf, delta=0, valid=1)
            else:
                s = lobes.thin_dielectric_sample(mat.base_color, mat.alpha, mat.ior, wo, u1, u2)
        else:
            s = lobes.thin_dielectric_sample(mat.base_color, mat.alpha, mat.ior, wo, u1, u2)
        return s

    @ti.func
    def _thin_eval(self, mat, wo, wi):
        """The thin wall's single-scattering lobe plus, with compensation, Kulla and Conty's lobe:
        per microfacet R + T = 1, so what the wall loses is a white GGX mirror's loss, 1 - E(mu_o),
        returned by the symmetric lobe of energy.py split into reflection and transmission in the
        slab's mean proportion."""
        value, pdf = lobes.thin_dielectric_eval(mat.base_color, mat.alpha, mat.ior, wo, wi)
        if ti.static(self.compensate):
            if mat.alpha > 0.0:
                r_share = self._thin_reflect_share(mat)
                wr = vec3(wi.x, wi.y, ti.abs(wi.z))
                v_ms, pdf_ms, share = self.energy.multiple_scattering(vec3(1.0), mat.alpha, wo, wr)
                part = r_share if wi.z > 0.0 else 1.0 - r_share
                tint = vec3(1.0) if wi.z > 0.0 else mat.base_color
                value += tint * v_ms * part
                pdf = (1.0 - share) * pdf + share * part * pdf_ms
        return value, pdf

    @ti.func
    def _thin_reflect_share(self, mat):
        """The share of the thin wall's multiple scattering that reflects: the slab reflectance at
        the mean Fresnel reflectance of its interface (any constant keeps the lobe reciprocal and
        its energy exact; this one follows the single-scattering split)."""
        f_avg = self.dielectric_tables.smooth_reflectance_average(mat.ior)
        return 2.0 * f_avg / (1.0 + f_avg)

    # --- the principled model's helpers (renderer/materials/principled.py calls them) --------------
    @ti.func
    def metal_eval(self, fresnel, f_avg, alpha, wo, wi):
        """A GGX metal lobe with Fresnel `fresnel` at the half vector (and its mean f_avg)."""
        value = vec3(0.0)
        pdf = 0.0
        if ti.static(not self.compensate):
            value, pdf = lobes.ggx_reflection_eval(fresnel, alpha, wo, wi)
        else:
            value, pdf = _compensated_reflection_eval(self.energy, fresnel, f_avg, alpha, wo, wi)
        return value, pdf

    @ti.func
    def metal_direction(self, alpha, wo, u1, u2):
        wi = vec3(0.0)
        if ti.static(not self.compensate):
            wi = lobes.ggx_reflection_direction(alpha, wo, u2)
        else:
            wi = _compensated_reflection_direction(self.energy, alpha, wo, u1, u2)
        return wi

    @ti.func
    def _local_coat_normal(self, mat, t, b, n_f):
        """The clearcoat's normal in the local frame, on wo's side ((0, 0, 1) without clearcoat)."""
        c = vec3(0.0, 0.0, 1.0)
        if ti.static(self.features.has_clearcoat):
            c = to_local(mat.coat_normal, t, b, n_f)
            if c.z < 0.0:
                c = -c
        return c

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
            if ti.static(self.features.has_principled):
                smooth = principled_has_smooth_part(self, mat)
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

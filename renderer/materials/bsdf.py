"""The BSDF over the device material table: shading, and dispatch to each material kind's lobes.

Each kind's lobes are in the module the registry names for it (renderer/materials/kinds.py):
diffuse.py (Lambert), conductor.py (GGX with a conductor's Fresnel), dielectric.py (smooth or
rough glass, or a thin wall), principled.py (glTF metallic-roughness with its clearcoat, sheen
and specular layers) and null_boundary.py (an invisible boundary, e.g. of a medium). `sample`,
`eval` and `flags` switch on the row's kind over the kinds `Features` compiles in, in registry
order. The lobes two kinds share stay here: glass (the dielectric and the principled glass lobe)
and GGX reflection with its multiple scattering (conductors and the principled metal lobe).

Only the kinds, layers and texture slots `Features` calls for are compiled in (`ti.static`).
Roughness 0 is an exact delta lobe, never a tiny GGX.

World-space API (n: the outward shading normal; wo: towards where the path came from):
  shade(surface, wo) -> (Material, n_shading)   textures, vertex colours and normal maps applied
  sample(mat, n, wo, u1, u2) -> BsdfSample      weight = f |cos| / pdf, pdf of the whole technique
  eval(mat, n, wo, wi) -> (f |cos|, pdf)        non-delta parts; pdf as `sample` would give wi
  flags(mat) -> LobeFlags bits                  which scattering the material has (pbrt's BxDFFlags)
  refracts(mat, ng, wo, wi) -> bool             whether wo -> wi crosses into another index

With `features.energy_compensation`, rough GGX reflection of conductors and of the principled
metal lobe adds Kulla and Conty's multiple-scattering lobe (renderer/materials/energy.py), so
rough metals no longer darken with roughness; rough dielectric interfaces (glass, the principled
glass lobe) add the lobe of renderer/materials/dielectric_energy.py, and rough thin walls the
GGX one, so white rough glass keeps all its light.
"""
import importlib

import taichi as ti

from renderer.geometry.shading import consistent_shading_normal
from renderer.materials import coated, lobes
from renderer.materials import microfacet as mf
from renderer.materials.lobes import BsdfSample
from renderer.materials.kinds import BACK_BLACK, KIND_IDS, KINDS, MAX_MIX_DEPTH, TANGENT_SPACE_MAP, TWO_SIDED
from renderer.materials.mapped_frames import frame_tangent, mapped_frame, material_weight
from renderer.materials.principled import principled_has_smooth_part
from renderer.materials.table import MIN_ALPHA, NO_TEXTURE, Material, alpha_of
from renderer.sampling.rng import pcg_hash
from renderer.sampling.warps import cosine_hemisphere, orthonormal_basis, to_local, to_world

vec3 = ti.math.vec3
# The kinds whose smooth part has_smooth_part cannot tell from the roughness alone.
_DIFFUSE, _NULL, _PRINCIPLED, _PLASTIC, _DISNEY, _COATED = (KIND_IDS[name] for name in
                                                             ("diffuse", "null", "principled", "plastic", "disney",
                                                              "coated"))


@ti.data_oriented
class Bsdf:
    """The BSDF over a material table, with only the lobes and textures `features` calls for."""

    def __init__(self, materials, features):
        self.materials = materials
        self.features = features
        # Energy compensation is a compile-time switch; the albedo tables exist only where used.
        self.compensate = features.energy_compensation
        self.energy = materials.ggx_albedo if self.compensate else None
        # (id, lobe module) of each kind compiled in, in registry order; refracting: the ids of
        # the kinds compiled in whose transmission changes the index (refracts).
        self.kinds = tuple((KIND_IDS[k.name], importlib.import_module(k.lobes)) for k in KINDS
                           if features.has_kind(k.name))
        self.refracting = tuple(KIND_IDS[k.name] for k in KINDS if k.refracts and features.has_kind(k.name))
        # Rough glass (the refracting kinds' glass lobes) with its multiple-scattering lobe; the
        # principled model's layering reads the same dielectric tables, compensated or not.
        self.compensate_glass = self.compensate and len(self.refracting) > 0
        self.dielectric_tables = (materials.dielectric_albedo if self.compensate_glass or features.has_kind("principled")
                                  else None)
        self.sheen_tables = materials.sheen_albedo if features.has_layer("sheen") else None

    @ti.func
    def shade(self, surface, wo):
        """The material at a surface point (textures and vertex colours applied) and the shading
        normal to use."""
        rec = self.materials.table[surface.material]
        if ti.static(self.features.has_mixes):
            rec = self._mixed(rec, surface, wo)
        n = surface.n_shading
        mat = Material(kind=rec.kind, base_color=rec.base_color, alpha=alpha_of(rec.roughness), metallic=rec.metallic,
                       transmission=rec.transmission, ior=rec.ior, emission=rec.emission, edge_tint=rec.edge_tint,
                       complex_ior=rec.complex_ior, eta=rec.eta, k=rec.k, fresnel_avg=rec.fresnel_avg, thin=rec.thin,
                       clearcoat=rec.clearcoat, clearcoat_alpha=alpha_of(rec.clearcoat_roughness),
                       sheen_color=rec.sheen_color, sheen_roughness=rec.sheen_roughness, specular=rec.specular,
                       specular_color=rec.specular_color, coat_normal=n, microfacet=0, nonlinear=0, plastic_table=-1,
                       internal_reflectance=0.0, specular_weight=0.0, sidedness=TWO_SIDED)
        if ti.static(self.features.has_emission):
            mat.two_sided_emission = rec.two_sided_emission
        if ti.static(self.features.has_sidedness):
            mat.sidedness = rec.sidedness
        if ti.static(self.features.has_microfacet_models):
            mat.microfacet = rec.microfacet
        if ti.static(self.features.has_anisotropy):
            # Mitsuba's frame: the lobe's x axis along dp/du (a mapped frame replaces it below).
            mat.alpha_v = mat.alpha if rec.roughness_v < 0.0 else alpha_of(rec.roughness_v)
            mat.tangent = frame_tangent(n, surface.dp_du)
        if ti.static(self.features.has_kind("plastic")):
            mat.nonlinear = rec.nonlinear
            mat.plastic_table = rec.plastic_table
            mat.internal_reflectance = rec.internal_reflectance
            mat.specular_weight = rec.specular_weight
        if ti.static(self.features.has_kind("disney")):
            mat.roughness, mat.anisotropic, mat.sheen, mat.sheen_tint = (rec.roughness, rec.anisotropic, rec.sheen,
                                                                         rec.sheen_tint)
            mat.spec_tint, mat.clearcoat_gloss, mat.flatness, mat.diff_trans = (rec.spec_tint, rec.clearcoat_gloss,
                                                                                rec.flatness, rec.diff_trans)
            mat.front_both_sides = rec.front_both_sides
        if ti.static(self.features.has_kind("coated")):
            mat.coat_base, mat.coat_thickness, mat.coat_albedo, mat.coat_g = (rec.coat_base, rec.coat_thickness,
                                                                              rec.coat_albedo, rec.coat_g)
            mat.coat_maxdepth, mat.coat_nsamples = rec.coat_maxdepth, rec.coat_nsamples
            mat.conductor_alpha = alpha_of(rec.conductor_roughness)
        if ti.static(self.features.has_kind("diffuse_transmission")):
            mat.transmittance = rec.transmittance
            if ti.static(self.features.has_textures):
                if rec.transmittance_texture != NO_TEXTURE:
                    mat.transmittance *= self.materials.textures.lookup(rec.transmittance_texture, surface).xyz
        if ti.static(self.features.has_vertex_colors):
            mat.base_color *= surface.color.xyz
        if ti.static(self.features.has_textures):
            tex = self.materials.textures
            if rec.textures[0] != NO_TEXTURE:
                mat.base_color *= tex.lookup(rec.textures[0], surface).xyz
            if rec.textures[1] != NO_TEXTURE:
                mr = tex.unfiltered(rec.textures[1], surface)
                mat.alpha = alpha_of(rec.roughness * mr.y)
                mat.metallic = rec.metallic * mr.z
            if rec.textures[3] != NO_TEXTURE:
                mat.emission *= tex.lookup(rec.textures[3], surface).xyz
            if rec.alpha_textures[0] != NO_TEXTURE:  # a textured width, alpha itself (rough: at least MIN_ALPHA)
                mat.alpha = ti.max(tex.unfiltered(rec.alpha_textures[0], surface).x, MIN_ALPHA)
                if ti.static(self.features.has_anisotropy):
                    if rec.roughness_v < 0.0 and rec.alpha_textures[1] == NO_TEXTURE:
                        mat.alpha_v = mat.alpha
            if ti.static(self.features.has_anisotropy):
                if rec.alpha_textures[1] != NO_TEXTURE:
                    mat.alpha_v = ti.max(tex.unfiltered(rec.alpha_textures[1], surface).x, MIN_ALPHA)
            if rec.transmission_texture != NO_TEXTURE:
                mat.transmission *= tex.lookup(rec.transmission_texture, surface).x
            if rec.specular_color_texture != NO_TEXTURE:
                mat.specular_color *= tex.lookup(rec.specular_color_texture, surface).xyz
            if rec.index_textures[0] != NO_TEXTURE:  # (the row's F_avg stays the untextured index's)
                mat.eta *= tex.unfiltered(rec.index_textures[0], surface).xyz
            if rec.index_textures[1] != NO_TEXTURE:
                mat.k *= tex.unfiltered(rec.index_textures[1], surface).xyz
            if ti.static(self.features.has_kind("disney")):
                if mat.kind == _DISNEY:
                    mat = _disney_textures(tex, rec, surface, mat)
            if ti.static(self.features.has_layer("clearcoat")):
                if rec.layer_textures[0] != NO_TEXTURE:
                    mat.clearcoat *= tex.lookup(rec.layer_textures[0], surface).x
                if rec.layer_textures[1] != NO_TEXTURE:
                    mat.clearcoat_alpha = alpha_of(rec.clearcoat_roughness
                                                   * tex.unfiltered(rec.layer_textures[1], surface).y)
            if ti.static(self.features.has_layer("sheen")):
                if rec.layer_textures[2] != NO_TEXTURE:
                    mat.sheen_color *= tex.lookup(rec.layer_textures[2], surface).xyz
                if rec.layer_textures[3] != NO_TEXTURE:
                    mat.sheen_roughness *= tex.unfiltered(rec.layer_textures[3], surface).w
            if ti.static(self.features.has_layer("specular")):
                if rec.layer_textures2[0] != NO_TEXTURE:
                    mat.specular *= tex.lookup(rec.layer_textures2[0], surface).w
                if rec.layer_textures2[1] != NO_TEXTURE:
                    mat.specular_color *= tex.lookup(rec.layer_textures2[1], surface).xyz
            if ti.static(self.features.has_mapped_frames):
                if rec.textures[2] != NO_TEXTURE and rec.normal_map_model != TANGENT_SPACE_MAP:
                    mapped, tangent, unmapped = mapped_frame(tex, rec.textures[2], rec.normal_map_model,
                                                             rec.normal_scale, surface, wo, self.features.has_bump_maps)
                    n, mat.tangent, mat.unmapped_normal, mat.coat_normal = mapped, tangent, unmapped, mapped
            if ti.static(self.features.has_normal_maps):
                if rec.textures[2] != NO_TEXTURE and rec.normal_map_model == TANGENT_SPACE_MAP:
                    n = _normal_mapped(tex, rec.textures[2], rec.normal_scale, surface, n, wo)
                mat.coat_normal = n
                if ti.static(self.features.has_layer("clearcoat")):
                    if rec.layer_textures2[2] != NO_TEXTURE:
                        mat.coat_normal = _normal_mapped(tex, rec.layer_textures2[2], rec.clearcoat_normal_scale,
                                                         surface, surface.n_shading, wo)
        return mat, n

    @ti.func
    def _mixed(self, rec, surface, wo):
        """The row a mix shades with at this point: its second material with probability its
        weight, else its first, down nested mixes, drawn from a hash of the point and wo (pbrt-v4's
        MixMaterial: one material per point, so light and BSDF sampling there see the same one; the
        image is the mix's in expectation). The mix keeps its own emission, medium and normal or
        bump map."""
        own = rec
        u = _point_uniform(surface.p, wo)
        for _ in ti.static(range(MAX_MIX_DEPTH)):
            if rec.mix[0] >= 0:
                w = rec.mix_weight
                if ti.static(self.features.has_textures):
                    if rec.mix[2] != NO_TEXTURE:
                        w *= self.materials.textures.lookup(rec.mix[2], surface).x
                w = ti.math.clamp(w, 0.0, 1.0)
                if u < w:
                    u = u / w
                    rec = self.materials.table[rec.mix[1]]
                else:
                    u = (u - w) / (1.0 - w)
                    rec = self.materials.table[rec.mix[0]]
        rec.emission = own.emission
        rec.textures[3] = own.textures[3]
        rec.medium = own.medium
        if own.textures[2] != NO_TEXTURE:
            rec.textures[2] = own.textures[2]
            rec.normal_map_model = own.normal_map_model
            rec.normal_scale = own.normal_scale
        return rec

    @ti.func
    def _frame(self, mat, n, wo_world):
        """The local frame on wo's side: the normal, and tangents along the material's oriented
        tangent in scenes with anisotropic lobes (else any)."""
        n_f = n if n.dot(wo_world) >= 0.0 else -n  # the side wo is on
        t, b = orthonormal_basis(n_f)
        if ti.static(self.features.has_anisotropy):
            along = mat.tangent - n_f * n_f.dot(mat.tangent)
            if along.dot(along) > 1e-12:
                t = ti.math.normalize(along)
                b = n_f.cross(t)
        return n_f, t, b

    @ti.func
    def sample(self, mat, n, wo_world, u1, u2):
        """Sample wi given wo; u1 picks a lobe, u2 the direction within it."""
        n_f, t, b = self._frame(mat, n, wo_world)
        wo = to_local(wo_world, t, b, n_f)
        entering = n.dot(wo_world) >= 0.0
        s = lobes.invalid_sample()
        if wo.z > 0.0:
            for kind_id, kind in ti.static(self.kinds):
                if mat.kind == kind_id:
                    s = kind.sample(self, mat, n_f, t, b, entering, wo, u1, u2)
        if s.valid == 1 and not _finite_positive(s.weight):
            s.valid = 0  # a numerically broken sample ends the path rather than reaching the film
        s.wi = to_world(s.wi, t, b, n_f)
        return s

    @ti.func
    def eval(self, mat, n, wo_world, wi_world):
        """f * |cos(wi)| and the pdf with which `sample` picks wi (non-delta lobes only)."""
        n_f, t, b = self._frame(mat, n, wo_world)
        wo = to_local(wo_world, t, b, n_f)
        wi = to_local(wi_world, t, b, n_f)
        entering = n.dot(wo_world) >= 0.0
        value = vec3(0.0)
        pdf = 0.0
        if wo.z > 0.0:
            for kind_id, kind in ti.static(self.kinds):
                if mat.kind == kind_id:
                    value, pdf = kind.evaluate(self, mat, n_f, t, b, entering, wo, wi)
        return value, pdf

    # --- glass: thick (refracting) or thin-walled, with multiple scattering where compensation is on ---
    @ti.func
    def glass_sample(self, mat, entering, wo, u1, u2):
        """The dielectric (or the principled glass lobe) with tint mat.base_color."""
        model, alpha_v = mf.row_model(self, mat), mf.row_alpha_v(self, mat)
        s = lobes.invalid_sample()
        thin = False
        if ti.static(self.features.has_thin):
            thin = mat.thin == 1
        if thin:
            if ti.static(self.features.has_thin):
                s = self._thin_sample(mat, wo, u1, u2)
        elif ti.static(self.compensate_glass):
            if mat.alpha > 0.0 and model == mf.GGX and alpha_v < 0.0:
                s = self.dielectric_tables.sample(mat.base_color, mat.alpha, _eta(mat, entering), wo, u1, u2)
            else:
                s = lobes.dielectric_sample(mat.base_color, mat.alpha, _eta(mat, entering), wo, u1, u2, model, alpha_v)
        else:
            s = lobes.dielectric_sample(mat.base_color, mat.alpha, _eta(mat, entering), wo, u1, u2, model, alpha_v)
        return s

    @ti.func
    def glass_eval(self, mat, entering, wo, wi):
        model, alpha_v = mf.row_model(self, mat), mf.row_alpha_v(self, mat)
        value = vec3(0.0)
        pdf = 0.0
        thin = False
        if ti.static(self.features.has_thin):
            thin = mat.thin == 1
        if thin:
            if ti.static(self.features.has_thin):
                value, pdf = self._thin_eval(mat, wo, wi)
        elif ti.static(self.compensate_glass):
            if mat.alpha > 0.0 and model == mf.GGX and alpha_v < 0.0:
                value, pdf = self.dielectric_tables.eval(mat.base_color, mat.alpha, _eta(mat, entering), wo, wi)
            else:
                value, pdf = lobes.dielectric_eval(mat.base_color, mat.alpha, _eta(mat, entering), wo, wi, model, alpha_v)
        else:
            value, pdf = lobes.dielectric_eval(mat.base_color, mat.alpha, _eta(mat, entering), wo, wi, model, alpha_v)
        return value, pdf

    @ti.func
    def glass_direction(self, mat, entering, wo, u1, u2):
        """(wi, valid): a direction as glass_sample draws it, for the principled mixture."""
        s = self.glass_sample(mat, entering, wo, u1, u2)
        return s.wi, s.valid

    @ti.func
    def _thin_sample(self, mat, wo, u1, u2):
        model, alpha_v = mf.row_model(self, mat), mf.row_alpha_v(self, mat)
        s = lobes.invalid_sample()
        if ti.static(self.compensate):
            if mat.alpha > 0.0 and model == mf.GGX and alpha_v < 0.0:
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
                                                          (u1 - share) / (1.0 - share), u2, model, alpha_v)
                    wi = single.wi
                    valid = single.valid
                if valid == 1:
                    value, pdf = self._thin_eval(mat, wo, wi)
                    if pdf > 0.0:
                        s = BsdfSample(wi=wi, weight=value / pdf, pdf=pdf, delta=0, valid=1)
            else:
                s = lobes.thin_dielectric_sample(mat.base_color, mat.alpha, mat.ior, wo, u1, u2, model, alpha_v)
        else:
            s = lobes.thin_dielectric_sample(mat.base_color, mat.alpha, mat.ior, wo, u1, u2, model, alpha_v)
        return s

    @ti.func
    def _thin_eval(self, mat, wo, wi):
        """The thin wall's single-scattering lobe plus, with compensation, Kulla and Conty's lobe:
        per microfacet R + T = 1, so what the wall loses is a white GGX mirror's loss, 1 - E(mu_o),
        returned by the symmetric lobe of energy.py split into reflection and transmission in the
        slab's mean proportion."""
        model, alpha_v = mf.row_model(self, mat), mf.row_alpha_v(self, mat)
        value, pdf = lobes.thin_dielectric_eval(mat.base_color, mat.alpha, mat.ior, wo, wi, model, alpha_v)
        if ti.static(self.compensate):
            if mat.alpha > 0.0 and model == mf.GGX and alpha_v < 0.0:
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
    def metal_eval(self, fresnel, f_avg, alpha, wo, wi, model=mf.GGX, alpha_v=mf.ISOTROPIC):
        """A metal lobe with Fresnel `fresnel` at the half vector (and its mean f_avg); the
        compensation's tables are isotropic GGX's, so other microfacet models and anisotropic
        widths go uncompensated."""
        value = vec3(0.0)
        pdf = 0.0
        if ti.static(not self.compensate):
            value, pdf = lobes.ggx_reflection_eval(fresnel, alpha, wo, wi, model, alpha_v)
        elif model != mf.GGX or alpha_v >= 0.0:
            value, pdf = lobes.ggx_reflection_eval(fresnel, alpha, wo, wi, model, alpha_v)
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
    def local_coat_normal(self, mat, t, b, n_f):
        """The clearcoat's normal in the local frame, on wo's side ((0, 0, 1) without clearcoat)."""
        c = vec3(0.0, 0.0, 1.0)
        if ti.static(self.features.has_layer("clearcoat")):
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
        if ti.static(self.features.has_mapped_frames):
            weight = material_weight(mat, n, wo, s.wi, self.features.has_sidedness)
            s.weight *= weight
            if weight <= 0.0:
                s.valid = 0
        if ti.static(self.features.has_sidedness):
            if mat.sidedness == BACK_BLACK and wo.dot(ng) < 0.0:
                s.valid = 0  # a one-sided BSDF seen from behind scatters nothing
        return s

    @ti.func
    def eval_at(self, mat, n, ng, wo, wi):
        """`eval` at a surface with geometric normal ng (see sample_at)."""
        value, pdf = self.eval(mat, n, wo, wi)
        if not _sides_agree(n, ng, wo, wi):
            value = vec3(0.0)
        if ti.static(self.features.has_mapped_frames):
            value *= material_weight(mat, n, wo, wi, self.features.has_sidedness)
        if ti.static(self.features.has_sidedness):
            if mat.sidedness == BACK_BLACK and wo.dot(ng) < 0.0:
                value = vec3(0.0)
        return value, pdf

    @ti.func
    def flags(self, mat):
        """The LobeFlags of the material (0 for a kind not compiled in)."""
        f = 0
        for kind_id, kind in ti.static(self.kinds):
            if mat.kind == kind_id:
                f = kind.flags(self, mat)
        return f

    @ti.func
    def has_smooth_part(self, mat):
        """Whether eval can be non-zero (light sampling is pointless on a purely delta BSDF): the
        same as `flags(mat) & NON_DELTA`, written as a switch on the kinds whose answer is not their
        roughness's (LLVM's fast-math code for the flags test rounds some images differently)."""
        smooth = mat.alpha > 0.0
        if mat.kind == _DIFFUSE or mat.kind == _PLASTIC or mat.kind == _DISNEY:  # diffuse bases; Disney has no delta
            smooth = True
        elif mat.kind == _NULL:
            smooth = False
        elif mat.kind == _COATED:  # pbrt's layered flags: delta only with a smooth coat over a smooth metal
            if ti.static(self.features.has_kind("coated")):
                smooth = coated.has_smooth_part(mat)
        elif mat.kind == _PRINCIPLED:
            if ti.static(self.features.has_kind("principled")):
                smooth = principled_has_smooth_part(self, mat)
        return smooth

    @ti.func
    def refracts(self, mat, ng, wo, wi):
        """Whether going from wo to wi crosses into another index (a kind that refracts, not a thin
        wall, wo and wi on opposite sides of the surface): radiance is scaled by 1 / eta^2 on the
        way, importance (photons) is not."""
        crosses = False
        for kind_id in ti.static(self.refracting):
            crosses = crosses or mat.kind == kind_id
        crosses = crosses and wo.dot(ng) * wi.dot(ng) < 0.0
        if ti.static(self.features.has_thin):
            crosses = crosses and mat.thin == 0  # a thin wall passes light on unscaled
        return crosses

    @ti.func
    def albedo(self, mat):
        """A display albedo (the albedo view, the denoiser's guide; not an integral of the BSDF): the
        base colour, or for a conductor given by its complex index (a named metal, eta and k), which
        ignores its base colour, its reflectance head-on: a gold box looks gold."""
        value = mat.base_color
        if ti.static(self.features.has_kind("conductor") or self.features.has_kind("coated")):
            if mat.complex_ior == 1:
                value = mf.head_on_reflectance(mat.eta, mat.k)
        return value


@ti.func
def _normal_mapped(tex, slot, scale, surface, n, wo):
    """The shading normal a tangent-space normal map gives at the surface (n where the surface
    has no tangents or the map's normal degenerates)."""
    result = n
    if surface.tangent.xyz.dot(surface.tangent.xyz) > 0.0:
        texel = tex.unfiltered(slot, surface).xyz * 2.0 - 1.0
        t = surface.tangent.xyz
        b = surface.tangent.w * n.cross(t)
        mapped = t * (texel.x * scale) + b * (texel.y * scale) + n * texel.z
        if mapped.dot(mapped) > 1e-12:
            result = consistent_shading_normal(ti.math.normalize(mapped), surface.n_geo, wo)
    return result


@ti.func
def _point_uniform(p, wo):
    """A uniform number in [0, 1) from the bits of a point and a direction."""
    k = ti.u32(0x9E3779B9)
    for i in ti.static(range(3)):
        k = pcg_hash(k ^ ti.bit_cast(p[i], ti.u32))
        k = pcg_hash(k ^ ti.bit_cast(wo[i], ti.u32))
    return ti.cast(k >> ti.u32(8), ti.f32) * (1.0 / 16777216.0)


@ti.func
def _times_texture(tex, slot, value, surface):
    """value times the first channel of the texture in `slot` (value where the slot is empty)."""
    result = value
    if slot != NO_TEXTURE:
        result = value * tex.unfiltered(slot, surface).x
    return result


@ti.func
def _disney_textures(tex, rec, surface, mat):
    """mat with the Disney kind's textured parameters (renderer/materials/kinds.py DISNEY_TEXTURED
    order) applied."""
    t1, t2, t3 = rec.disney_textures, rec.disney_textures2, rec.disney_textures3
    mat.roughness = _times_texture(tex, t1[0], mat.roughness, surface)
    mat.anisotropic = _times_texture(tex, t1[1], mat.anisotropic, surface)
    mat.metallic = _times_texture(tex, t1[2], mat.metallic, surface)
    mat.sheen = _times_texture(tex, t1[3], mat.sheen, surface)
    mat.sheen_tint = _times_texture(tex, t2[0], mat.sheen_tint, surface)
    mat.spec_tint = _times_texture(tex, t2[1], mat.spec_tint, surface)
    mat.clearcoat = _times_texture(tex, t2[2], mat.clearcoat, surface)
    mat.clearcoat_gloss = _times_texture(tex, t2[3], mat.clearcoat_gloss, surface)
    mat.flatness = _times_texture(tex, t3[0], mat.flatness, surface)
    mat.diff_trans = _times_texture(tex, t3[1], mat.diff_trans, surface)
    return mat


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


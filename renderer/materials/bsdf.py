"""The material table on the device and its BSDF.

Kinds: diffuse (Lambert), conductor (GGX, Schlick F0 = base colour), dielectric (smooth or rough
glass, Walter et al. 2007) and principled (glTF metallic-roughness: a metal lobe, a transmissive
dielectric lobe and a dielectric-coated diffuse base, mixed by metallic and transmission, with
base-colour, metallic-roughness, normal, emissive and transmission textures).

Which kinds and texture slots are compiled in is decided by `Features` (`ti.static`), so a scene
without glass carries no refraction code and an untextured scene no texture lookups. Roughness 0
is an exact delta lobe, never a tiny GGX.

Frames: `n` is the outward shading normal, `wo` points back along the incoming ray. Sampling
returns `weight = f * |cos| / pdf`, the factor a path's throughput is multiplied by.
"""
import numpy as np
import taichi as ti

from renderer.geometry.shading import consistent_shading_normal
from renderer.materials import microfacet as mf
from renderer.materials.texture_sampler import TextureTable
from renderer.sampling.warps import INV_PI, cosine_hemisphere, orthonormal_basis, to_local, to_world

DIFFUSE, CONDUCTOR, DIELECTRIC, PRINCIPLED = 0, 1, 2, 3
KIND_IDS = {"diffuse": DIFFUSE, "conductor": CONDUCTOR, "dielectric": DIELECTRIC, "principled": PRINCIPLED}
NO_TEXTURE = -1

# Only roughness == 0 is a delta lobe. Any other roughness is clamped to at least this GGX width so
# that D(h) <= 1/(pi a^2) ~ 3e7 stays finite in f32.
MIN_ALPHA = 1e-4

vec3 = ti.math.vec3

# As stored: one row per material. Texture slots hold a texture-table index or NO_TEXTURE:
# textures = (base colour, metallic-roughness, normal, emissive), transmission_texture separately.
MaterialRecord = ti.types.struct(kind=ti.i32, base_color=vec3, roughness=ti.f32, metallic=ti.f32,
                                 transmission=ti.f32, ior=ti.f32, emission=vec3, normal_scale=ti.f32,
                                 textures=ti.math.ivec4, transmission_texture=ti.i32)
# As shaded: a record with its textures applied at one surface point.
Material = ti.types.struct(kind=ti.i32, base_color=vec3, alpha=ti.f32, metallic=ti.f32, transmission=ti.f32,
                           ior=ti.f32, emission=vec3)
BsdfSample = ti.types.struct(wi=vec3, weight=vec3, pdf=ti.f32, delta=ti.i32, valid=ti.i32)


def alpha_from_roughness(roughness):
    return 0.0 if roughness == 0.0 else max(roughness * roughness, MIN_ALPHA)


@ti.func
def _alpha(roughness):
    return 0.0 if roughness <= 0.0 else ti.max(roughness * roughness, MIN_ALPHA)


class MaterialRows:
    """Numpy rows for the device table, from scene materials and model-file materials."""

    def __init__(self):
        self.rows = []

    def add_spec(self, spec) -> int:
        self.rows.append(dict(kind=KIND_IDS[spec.kind], base_color=spec.base_color, roughness=spec.roughness,
                              metallic=spec.metallic, transmission=spec.transmission, ior=spec.ior,
                              emission=spec.emission, normal_scale=1.0, textures=(NO_TEXTURE,) * 4,
                              transmission_texture=NO_TEXTURE))
        return len(self.rows) - 1

    def add_pbr(self, pbr, texture_id) -> int:
        """A glTF material; texture_id maps its TextureRef to a texture-table index."""
        def tex(ref):
            return NO_TEXTURE if ref is None else texture_id(ref)

        self.rows.append(dict(kind=PRINCIPLED, base_color=tuple(pbr.base_color_factor[:3]),
                              roughness=pbr.roughness_factor, metallic=pbr.metallic_factor,
                              transmission=pbr.transmission_factor, ior=pbr.ior,
                              emission=tuple(pbr.emissive_factor), normal_scale=pbr.normal_scale,
                              textures=(tex(pbr.base_color_texture), tex(pbr.metallic_roughness_texture),
                                        tex(pbr.normal_texture), tex(pbr.emissive_texture)),
                              transmission_texture=tex(pbr.transmission_texture)))
        return len(self.rows) - 1

    def arrays(self) -> dict:
        def col(name, dtype, width=None):
            values = [r[name] for r in self.rows]
            a = np.array(values, dtype)
            return a.reshape(len(values), width) if width else a

        return {"kind": col("kind", np.int32), "base_color": col("base_color", np.float32, 3),
                "roughness": col("roughness", np.float32), "metallic": col("metallic", np.float32),
                "transmission": col("transmission", np.float32), "ior": col("ior", np.float32),
                "emission": col("emission", np.float32, 3), "normal_scale": col("normal_scale", np.float32),
                "textures": col("textures", np.int32, 4),
                "transmission_texture": col("transmission_texture", np.int32)}

    def uses(self) -> dict:
        """Which kinds and texture slots occur (for Features)."""
        kinds = {r["kind"] for r in self.rows}
        slots = [any(r["textures"][i] != NO_TEXTURE for r in self.rows) for i in range(4)]
        return {"kinds": kinds, "textures": any(slots) or any(r["transmission_texture"] != NO_TEXTURE for r in self.rows),
                "normal_maps": slots[2], "emission": any(max(r["emission"]) > 0 for r in self.rows)}


@ti.data_oriented
class MaterialTable:
    """All of a scene's materials in one struct field, indexed by material id, and its textures."""

    def __init__(self, rows: MaterialRows, textures: TextureTable | None = None):
        arrays = rows.arrays()
        self.count = len(arrays["kind"])
        self.table = MaterialRecord.field(shape=max(1, self.count))
        if self.count:
            self.table.from_numpy(arrays)
        self.textures = textures or TextureTable(None, [])

    @classmethod
    def from_specs(cls, specs):
        rows = MaterialRows()
        for spec in specs:
            rows.add_spec(spec)
        return cls(rows)


@ti.data_oriented
class Bsdf:
    """The BSDF over a material table, with only the lobes and textures `features` calls for."""

    def __init__(self, materials: MaterialTable, features):
        self.materials = materials
        self.features = features

    @ti.func
    def shade(self, surface, wo):
        """The material at a surface point (textures applied) and the shading normal to use."""
        rec = self.materials.table[surface.material]
        mat = Material(kind=rec.kind, base_color=rec.base_color, alpha=_alpha(rec.roughness), metallic=rec.metallic,
                       transmission=rec.transmission, ior=rec.ior, emission=rec.emission)
        n = surface.n_shading
        if ti.static(self.features.has_textures):
            tex = self.materials.textures
            if rec.textures[0] != NO_TEXTURE:
                mat.base_color *= tex.sample(rec.textures[0], surface.uv, surface.uv1).xyz
            if rec.textures[1] != NO_TEXTURE:
                mr = tex.sample(rec.textures[1], surface.uv, surface.uv1)
                mat.alpha = _alpha(rec.roughness * mr.y)
                mat.metallic = rec.metallic * mr.z
            if rec.textures[3] != NO_TEXTURE:
                mat.emission *= tex.sample(rec.textures[3], surface.uv, surface.uv1).xyz
            if rec.transmission_texture != NO_TEXTURE:
                mat.transmission *= tex.sample(rec.transmission_texture, surface.uv, surface.uv1).x
            if ti.static(self.features.has_normal_maps):
                if rec.textures[2] != NO_TEXTURE and surface.tangent.xyz.dot(surface.tangent.xyz) > 0.0:
                    texel = tex.sample(rec.textures[2], surface.uv, surface.uv1).xyz * 2.0 - 1.0
                    t = surface.tangent.xyz
                    b = surface.tangent.w * n.cross(t)
                    mapped = t * (texel.x * rec.normal_scale) + b * (texel.y * rec.normal_scale) + n * texel.z
                    if mapped.dot(mapped) > 1e-12:
                        n = consistent_shading_normal(ti.math.normalize(mapped), surface.n_geo, wo)
        return mat, n

    @ti.func
    def sample(self, mat, n, wo_world, u):
        """Sample wi given wo. u is a vec3 of uniforms (lobe choice, 2D direction)."""
        n_f = n if n.dot(wo_world) >= 0.0 else -n  # the side wo is on
        t, b = orthonormal_basis(n_f)
        wo = to_local(wo_world, t, b, n_f)
        entering = n.dot(wo_world) >= 0.0
        s = BsdfSample(wi=vec3(0.0, 0.0, 1.0), weight=vec3(0.0), pdf=0.0, delta=0, valid=0)
        if wo.z > 0.0:
            if ti.static(self.features.has_diffuse):
                if mat.kind == DIFFUSE:
                    s = _sample_diffuse(mat.base_color, wo, u)
            if ti.static(self.features.has_conductor):
                if mat.kind == CONDUCTOR:
                    s = _sample_conductor(mat.base_color, mat.alpha, wo, u)
            if ti.static(self.features.has_dielectric):
                if mat.kind == DIELECTRIC:
                    s = _sample_dielectric(mat.base_color, mat.alpha, mat.ior if entering else 1.0 / mat.ior, wo, u)
            if ti.static(self.features.has_principled):
                if mat.kind == PRINCIPLED:
                    s = _sample_principled(mat, entering, wo, u)
        s.wi = to_world(s.wi, t, b, n_f)
        return s

    @ti.func
    def eval(self, mat, n, wo_world, wi_world):
        """f * |cos(wi)| and the solid-angle pdf of sampling wi, for the non-delta reflection lobes
        of diffuse and conductor materials (the light-transport integrators extend this)."""
        n_f = n if n.dot(wo_world) >= 0.0 else -n
        t, b = orthonormal_basis(n_f)
        wo = to_local(wo_world, t, b, n_f)
        wi = to_local(wi_world, t, b, n_f)
        value = vec3(0.0)
        pdf = 0.0
        if wo.z > 0.0 and wi.z > 0.0:
            if ti.static(self.features.has_diffuse):
                if mat.kind == DIFFUSE:
                    value = mat.base_color * (wi.z * INV_PI)
                    pdf = wi.z * INV_PI
            if ti.static(self.features.has_conductor):
                if mat.kind == CONDUCTOR and mat.alpha > 0.0:
                    value, pdf = _eval_ggx_reflection(mf.fresnel_schlick(mat.base_color, wo.dot(ti.math.normalize(wo + wi))),
                                                      mat.alpha, wo, wi)
        return value, pdf

    @ti.func
    def albedo(self, mat):
        """A display albedo for the debug view (not an integral of the BSDF)."""
        return mat.base_color


@ti.func
def _eval_ggx_reflection(f, alpha, wo, wi):
    h = ti.math.normalize(wo + wi)
    value = f * mf.ggx_d(h, alpha) * mf.smith_g2(wo, wi, alpha) / (4.0 * wo.z)
    pdf = mf.visible_normal_pdf(wo, h, alpha) / (4.0 * wo.dot(h))
    return value, pdf


@ti.func
def _sample_diffuse(albedo, wo, u):
    wi = cosine_hemisphere(ti.math.vec2(u.y, u.z))
    return BsdfSample(wi=wi, weight=albedo, pdf=wi.z * INV_PI, delta=0, valid=1)


@ti.func
def _sample_conductor(f0, alpha, wo, u):
    s = BsdfSample(wi=vec3(-wo.x, -wo.y, wo.z), weight=vec3(0.0), pdf=1.0, delta=1, valid=1)
    if alpha == 0.0:
        s.weight = mf.fresnel_schlick(f0, wo.z)
    else:
        h = mf.sample_visible_normal(wo, alpha, ti.math.vec2(u.y, u.z))
        wi = mf.reflect(wo, h)
        s.delta = 0
        if wi.z > 0.0:
            cos_oh = wo.dot(h)
            s.wi = wi
            # f cos / pdf with pdf = G1 D (wo.h) / (4 wo.z wo.h): D and the Jacobian cancel.
            s.weight = mf.fresnel_schlick(f0, cos_oh) * (mf.smith_g2(wo, wi, alpha) / mf.smith_g1(wo, alpha))
            s.pdf = mf.visible_normal_pdf(wo, h, alpha) / (4.0 * cos_oh)
        else:
            s.valid = 0
    return s


@ti.func
def _sample_dielectric(tint, alpha, eta, wo, u):
    """eta = n on the far side / n on wo's side. Lobe choice by Fresnel, so F cancels in the weight.

    Transmission scales radiance by 1/eta^2 (radiance is not conserved across a change of
    index; Veach 1997, 5.2); a round trip in and out of a solid multiplies to 1.
    """
    s = BsdfSample(wi=vec3(0.0, 0.0, 1.0), weight=vec3(0.0), pdf=0.0, delta=1, valid=1)
    h = vec3(0.0, 0.0, 1.0)
    g_ratio = 1.0
    if alpha > 0.0:
        h = mf.sample_visible_normal(wo, alpha, ti.math.vec2(u.y, u.z))
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
        if alpha > 0.0:
            g_ratio = mf.smith_g2(wo, s.wi, alpha) / mf.smith_g1(wo, alpha)
            d_vis = mf.visible_normal_pdf(wo, h, alpha)
            if reflect:
                s.pdf = f * d_vis / (4.0 * cos_oh)
            else:
                # Walter et al. 2007, eq. 17: d(h)/d(wi) = eta^2 |wi.h| / (wo.h + eta wi.h)^2
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


@ti.func
def _sample_principled(mat, entering, wo, u):
    """Stochastic lobe selection: metal with probability `metallic`, transmission with
    (1 - metallic) transmission, else the coated diffuse base. Each lobe's estimate is
    unbiased for its share, so the mixture is unbiased whatever the weights."""
    s = BsdfSample(wi=vec3(0.0, 0.0, 1.0), weight=vec3(0.0), pdf=0.0, delta=0, valid=0)
    pick = u.x
    p_metal = mat.metallic
    p_trans = (1.0 - mat.metallic) * mat.transmission
    if pick < p_metal:
        s = _sample_conductor(mat.base_color, mat.alpha, wo, vec3(pick / p_metal, u.y, u.z))
    elif pick < p_metal + p_trans:
        eta = mat.ior if entering else 1.0 / mat.ior
        s = _sample_dielectric(mat.base_color, mat.alpha, eta, wo, vec3((pick - p_metal) / p_trans, u.y, u.z))
    else:
        p_base = 1.0 - p_metal - p_trans
        s = _sample_coated_diffuse(mat, wo, vec3((pick - p_metal - p_trans) / p_base, u.y, u.z))
    return s


@ti.func
def _sample_coated_diffuse(mat, wo, u):
    """A dielectric specular layer (GGX, Fresnel with the material's ior) over a Lambertian base
    whose light is what the layer does not reflect: f = F(wo.h) D G / (4 wo.z) + (1 - F(wo.z))
    base / pi. Specular is picked with probability F(wo.z); both lobes' pdfs combine (one-sample
    MIS over lobes) so the weight stays bounded when a rough specular sample lands anywhere."""
    f_view, _ = mf.fresnel_dielectric(wo.z, mat.ior)
    p_spec = ti.math.clamp(f_view, 0.05, 0.95)  # never starve either lobe
    s = BsdfSample(wi=vec3(0.0, 0.0, 1.0), weight=vec3(0.0), pdf=0.0, delta=0, valid=1)
    if mat.alpha == 0.0:
        # Delta coat: reflect with probability F, else diffuse; both weights are exact.
        if u.x < f_view:
            s.wi = vec3(-wo.x, -wo.y, wo.z)
            s.weight = vec3(1.0)
            s.pdf = f_view
            s.delta = 1
        else:
            s.wi = cosine_hemisphere(ti.math.vec2(u.y, u.z))
            s.weight = mat.base_color
            s.pdf = (1.0 - f_view) * s.wi.z * INV_PI
    else:
        if u.x < p_spec:
            s.wi = mf.reflect(wo, mf.sample_visible_normal(wo, mat.alpha, ti.math.vec2(u.y, u.z)))
        else:
            s.wi = cosine_hemisphere(ti.math.vec2(u.y, u.z))
        if s.wi.z <= 0.0:
            s.valid = 0
        else:
            h = ti.math.normalize(wo + s.wi)
            f_h, _ = mf.fresnel_dielectric(ti.max(wo.dot(h), 1e-6), mat.ior)
            spec, pdf_spec = _eval_ggx_reflection(vec3(f_h), mat.alpha, wo, s.wi)
            diffuse = mat.base_color * ((1.0 - f_view) * s.wi.z * INV_PI)
            s.pdf = p_spec * pdf_spec + (1.0 - p_spec) * s.wi.z * INV_PI
            s.weight = (spec + diffuse) / s.pdf
    return s

"""The material table on the device: one struct row per material, and texture slots.

Rows come from scene-file materials (`MaterialSpec`) and from model files (glTF metallic-roughness
`PbrMaterial`, with textures). `Bsdf.shade` turns a row into the `Material` at a surface point.
"""
import numpy as np
import taichi as ti

from renderer.materials.coat_bases import COAT_BASES
from renderer.materials.conductor_ior import conductor_ior_row
from renderer.materials.dispersion import dispersion_row
from renderer.materials.kinds import (COLUMNS, DISNEY_TEXTURED, KIND_IDS, KIND_NAMES, LAYER_COLUMNS, LAYERS, NO_MEDIUM, NO_TEXTURE,
                                      BACK_BLACK, BACK_CULLED, MIN_ALPHA, SCENE_MEDIUM, SIDEDNESS, TANGENT_SPACE_MAP,
                                      TWO_SIDED,
                                      alpha_from_roughness,
                                      compensated_when_rough)  # noqa: F401 (re-exported)
from renderer.materials.mapped_frame_rows import mapped_frame_uses, normal_map_row, oriented_rows
from renderer.materials.microfacet import GGX, MODELS
from renderer.materials.plastic_tables import plastic_row
from renderer.materials.texture_sampler import TextureTable
from renderer.runtime.upload import upload_fields

vec3 = ti.math.vec3

# glTF allows ior = 1 (no refraction at all); the rough-dielectric half vector wo + eta wi is then
# zero for the transmitted direction. Just above 1 the interface is as good as invisible and finite.
MIN_IOR = 1.0001


# As stored: one row per material, its members the registry's columns (renderer/materials/
# kinds.py says what each holds and to which kind or layer it belongs). Texture slots hold a
# texture-table index or NO_TEXTURE. medium: the participating medium inside the material's
# surfaces, or NO_MEDIUM. complex_ior = 1: a conductor whose Fresnel is exact from eta + i k,
# with its cosine-weighted average fresnel_avg precomputed (renderer/materials/conductor_ior.py).
# alpha_mode, alpha_cutoff and base_alpha: glTF coverage, tested in traversal. thin = 1: a
# thin-walled transmitter, whose transmission passes straight through instead of refracting.
_TYPES = {"i32": ti.i32, "f32": ti.f32, "vec3": vec3, "vec4": ti.math.vec4, "ivec4": ti.math.ivec4}
MaterialRecord = ti.types.struct(**{c.name: _TYPES[c.type] for c in COLUMNS})
# As shaded: a record with its textures applied at one surface point. coat_normal: the clearcoat's
# shading normal (its own normal map, else the base's normal). unmapped_normal: where a Mitsuba
# normal or bump map tilted the shading normal, the normal before it (on the viewer's side), whose
# frame `Bsdf.eval_at` / `sample_at` weigh scattering in (renderer/materials/mapped_frames.py);
# zero elsewhere. tangent: the mapped frame's tangent (Mitsuba's, for anisotropic lobes); zero
# where no map set it.
Material = ti.types.struct(kind=ti.i32, base_color=vec3, alpha=ti.f32, metallic=ti.f32, transmission=ti.f32,
                           ior=ti.f32, emission=vec3, edge_tint=vec3, complex_ior=ti.i32, eta=vec3, k=vec3,
                           fresnel_avg=vec3, thin=ti.i32, clearcoat=ti.f32, clearcoat_alpha=ti.f32,
                           sheen_color=vec3, sheen_roughness=ti.f32, specular=ti.f32, specular_color=vec3,
                           coat_normal=vec3, microfacet=ti.i32, nonlinear=ti.i32, plastic_table=ti.i32,
                           internal_reflectance=ti.f32, specular_weight=ti.f32, sidedness=ti.i32,
                           unmapped_normal=vec3, tangent=vec3, alpha_v=ti.f32,
                           # Disney's (renderer/materials/disney.py): the perceptual roughness
                           # itself, and the weights of its lobes and tints.
                           roughness=ti.f32, anisotropic=ti.f32, sheen=ti.f32, sheen_tint=ti.f32,
                           spec_tint=ti.f32, clearcoat_gloss=ti.f32, flatness=ti.f32, diff_trans=ti.f32,
                           front_both_sides=ti.i32,
                           # The coated kind's (renderer/materials/coated.py).
                           coat_base=ti.i32, coat_thickness=ti.f32, coat_albedo=vec3, coat_g=ti.f32,
                           coat_maxdepth=ti.i32, coat_nsamples=ti.i32, conductor_alpha=ti.f32,
                           transmittance=vec3,  # diffuse_transmission's
                           two_sided_emission=ti.i32)

ALPHA_OPAQUE, ALPHA_MASK, ALPHA_BLEND = 0, 1, 2
ALPHA_MODE_IDS = {"OPAQUE": ALPHA_OPAQUE, "MASK": ALPHA_MASK, "BLEND": ALPHA_BLEND}


@ti.func
def alpha_of(roughness):
    return 0.0 if roughness <= 0.0 else ti.max(roughness * roughness, MIN_ALPHA)


class MaterialRows:
    """Numpy rows for the device table, from scene materials and model-file materials; a row
    starts from the registry's column defaults."""

    def __init__(self, medium_names: tuple[str, ...] = ()):
        self.rows = []
        self.medium_ids = {name: i for i, name in enumerate(medium_names)}
        self.plastic_tables: list[np.ndarray] = []  # renderer/materials/plastic_tables.py, one per rough plastic
        # The rows of mixes' parts wait until every material has its row: primitives name a
        # material by its place in the scene's list, which must be its row (_place_mix_parts).
        self._mix_parts: list[tuple] = []  # (mix row, parts, their texture slots by role)

    @classmethod
    def of_specs(cls, specs, medium_names: tuple[str, ...] = ()) -> "MaterialRows":
        """The rows of scene materials without textures (an SDF scene's)."""
        rows = cls(medium_names)
        for spec in specs:
            rows.add_spec(spec)
        return rows

    def add_spec(self, spec, texture_slots: dict | None = None) -> int:
        """A scene file's material; texture_slots: the texture-table index of each of its textures
        by role (MaterialSpec.textures)."""
        slots = texture_slots or {}
        row = _default_row()
        row.update({c.name: getattr(spec, c.name) for c in COLUMNS if c.from_spec})
        row["textures"] = (slots.get("base_color", NO_TEXTURE), row["textures"][1],
                           slots.get("normal", slots.get("bump", NO_TEXTURE)), slots.get("emission", NO_TEXTURE))
        row.update(normal_map_row(spec, slots))
        row.update(kind=KIND_IDS[spec.kind], medium=self.medium_ids[spec.medium] if spec.medium else NO_MEDIUM,
                   outside_medium=self.medium_ids[spec.outside_medium] if spec.outside_medium else SCENE_MEDIUM,
                   thin=int(spec.thin), microfacet=MODELS[spec.microfacet], sidedness=SIDEDNESS[spec.sidedness],
                   roughness_v=-1.0 if spec.roughness_v is None else float(spec.roughness_v),
                   alpha_textures=(slots.get("alpha", NO_TEXTURE), slots.get("alpha_v", NO_TEXTURE), NO_TEXTURE,
                                   NO_TEXTURE),
                   **dispersion_row(spec), **conductor_ior_row(spec))
        row["specular_color_texture"] = slots.get("specular_color", NO_TEXTURE)
        row["transmittance_texture"] = slots.get("transmittance", NO_TEXTURE)
        row["index_textures"] = (slots.get("eta", NO_TEXTURE), slots.get("k", NO_TEXTURE), NO_TEXTURE, NO_TEXTURE)
        if spec.opacity < 1.0 or "opacity" in slots:
            row.update(alpha_mode=ALPHA_BLEND, base_alpha=spec.opacity,
                       opacity_texture=slots.get("opacity", NO_TEXTURE))
        if spec.kind == "plastic":
            row.update(plastic_row(spec, self.plastic_tables))
        if spec.kind == "disney":
            row.update(_disney_texture_row(slots))
        if spec.kind == "coated":
            row["coat_base"] = COAT_BASES[spec.coat_base]
        self.rows.append(row)
        index = len(self.rows) - 1
        if spec.mix is not None:
            part_slots = [{role.split(".", 1)[1]: slot for role, slot in slots.items() if role.startswith(f"mix{i}.")}
                          for i in range(len(spec.mix))]
            self._mix_parts.append((index, spec.mix, part_slots, slots.get("mix_weight", NO_TEXTURE)))
        return index

    def _place_mix_parts(self) -> None:
        """The rows of the mixes' parts, after all the others (parts of parts after those)."""
        while self._mix_parts:
            pending, self._mix_parts = self._mix_parts, []
            for index, parts, part_slots, weight in pending:
                ids = [self.add_spec(part, slots) for part, slots in zip(parts, part_slots)]
                self.rows[index]["mix"] = (ids[0], ids[1], weight, NO_TEXTURE)
                self.rows[index]["kind"] = self.rows[ids[0]]["kind"]  # a mix row is never shaded as itself

    def add_medium(self, name: str) -> int:
        """Registers a medium that the scene's own list does not name (a model file's volume)."""
        if name not in self.medium_ids:
            self.medium_ids[name] = len(self.medium_ids)
        return self.medium_ids[name]

    def add_pbr(self, pbr, texture_id, medium: int = NO_MEDIUM) -> int:
        """A glTF material; texture_id maps its TextureRef to a texture-table index; medium: the
        medium inside (KHR_materials_volume), registered with add_medium."""
        def tex(ref):
            return NO_TEXTURE if ref is None else texture_id(ref)

        row = _default_row()
        row.update({c.name: getattr(pbr, c.gltf) for c in LAYER_COLUMNS if c.gltf})
        row.update(kind=KIND_IDS["principled"], base_color=tuple(pbr.base_color_factor[:3]),
                   roughness=pbr.roughness_factor, metallic=pbr.metallic_factor,
                   transmission=pbr.transmission_factor, ior=max(pbr.ior, MIN_IOR),
                   emission=tuple(pbr.emissive_factor), normal_scale=pbr.normal_scale,
                   textures=(tex(pbr.base_color_texture), tex(pbr.metallic_roughness_texture),
                             tex(pbr.normal_texture), tex(pbr.emissive_texture)),
                   transmission_texture=tex(pbr.transmission_texture), medium=medium,
                   layer_textures=(tex(pbr.clearcoat_texture), tex(pbr.clearcoat_roughness_texture),
                                   tex(pbr.sheen_color_texture), tex(pbr.sheen_roughness_texture)),
                   layer_textures2=(tex(pbr.specular_texture), tex(pbr.specular_color_texture),
                                    tex(pbr.clearcoat_normal_texture), NO_TEXTURE),
                   alpha_mode=ALPHA_MODE_IDS.get(pbr.alpha_mode, ALPHA_OPAQUE), alpha_cutoff=pbr.alpha_cutoff,
                   base_alpha=pbr.base_color_factor[3],
                   # glTF culls the back faces of single-sided materials; a transmitting one keeps
                   # them (light inside a glass or a volume leaves through them).
                   sidedness=TWO_SIDED if pbr.double_sided or pbr.transmission_factor > 0.0 or medium != NO_MEDIUM
                   else BACK_CULLED,
                   thin=int(pbr.transmission_factor > 0.0 and pbr.thin_walled))
        self.rows.append(row)
        return len(self.rows) - 1

    def arrays(self) -> dict:
        """One array per MaterialRecord member, its dtype and width read off the record."""
        self._place_mix_parts()
        out = {}
        for name, member in MaterialRecord.members.items():
            width = getattr(member, "n", None)
            dtype = np.int32 if (getattr(member, "dtype", member) == ti.i32) else np.float32
            a = np.array([r[name] for r in self.rows], dtype)
            out[name] = a.reshape(len(self.rows), width) if width else a
        return out

    def uses(self) -> dict:
        """What the rows call for (for Features): the names of the kinds and layers they use,
        texture use, and the rest of features_from's material_uses."""
        self._place_mix_parts()
        rows = self.rows
        slots = [any(r["textures"][i] != NO_TEXTURE for r in rows) for i in range(4)]
        layer_textures = any(t != NO_TEXTURE for r in rows for t in (*r["layer_textures"], *r["layer_textures2"]))
        return {"kinds": {KIND_NAMES[r["kind"]] for r in rows},
                "layers": {layer.name for layer in LAYERS if any(layer.in_use(r) for r in rows)},
                "textures": (any(slots) or layer_textures
                             or any(r["transmission_texture"] != NO_TEXTURE or r["transmittance_texture"] != NO_TEXTURE
                                    for r in rows)
                             or any(t != NO_TEXTURE for r in rows for c in _DISNEY_TEXTURE_COLUMNS for t in r[c])
                             or any(r["mix"][2] != NO_TEXTURE or r["specular_color_texture"] != NO_TEXTURE
                                    or r["index_textures"][0] != NO_TEXTURE or r["index_textures"][1] != NO_TEXTURE
                                    for r in rows)
                             or any(t != NO_TEXTURE for r in rows for t in r["alpha_textures"])),
                "normal_maps": any(r["textures"][2] != NO_TEXTURE and r["normal_map_model"] == TANGENT_SPACE_MAP
                                   for r in rows),
                **mapped_frame_uses(rows), "emission": any(max(r["emission"]) > 0 for r in rows),
                "media": any(r["medium"] != NO_MEDIUM or r["outside_medium"] >= 0 for r in rows),
                "dispersion": any(r["dispersion"] != 0 for r in rows),
                "rough": any(compensated_when_rough(KIND_NAMES[r["kind"]]) and r["roughness"] > 0.0 for r in rows),
                "alpha": any(r["alpha_mode"] != ALPHA_OPAQUE for r in rows),
                "thin": any(r["thin"] == 1 for r in rows),
                "microfacet_models": any(r["microfacet"] != GGX for r in rows),
                "mixes": any(r["mix"][0] >= 0 for r in rows),
                "sidedness": any(r["sidedness"] == BACK_BLACK for r in rows),
                "anisotropy": bool(rows) and bool(oriented_rows(self.arrays()).any())}


# The Disney kind's texture slots: DISNEY_TEXTURED's parameters four to a column, in order (the
# last, transmission, has the shared transmission_texture column).
_DISNEY_TEXTURE_COLUMNS = ("disney_textures", "disney_textures2", "disney_textures3")


def _disney_texture_row(slots: dict) -> dict:
    ids = [slots.get(name, NO_TEXTURE) for name in DISNEY_TEXTURED]
    row = {column: tuple((ids[4 * i:4 * i + 4] + [NO_TEXTURE] * 4)[:4]) for i, column in enumerate(_DISNEY_TEXTURE_COLUMNS)}
    row["transmission_texture"] = slots.get("transmission", NO_TEXTURE)
    return row


def _default_row() -> dict:
    return {c.name: c.default for c in COLUMNS}


@ti.data_oriented
class MaterialTable:
    """All of a scene's materials in one struct field, indexed by material id, and its textures."""

    def __init__(self, rows: MaterialRows, textures: TextureTable | None = None, volume_media: tuple = ()):
        arrays = rows.arrays()
        # Media that model files' materials fill their interiors with (glTF volumes): the media
        # table numbers them after the scene's own.
        self.volume_media = tuple(volume_media)
        self.arrays = arrays  # kept: direct lighting reads emission per material
        self.count = len(arrays["kind"])
        self.table = MaterialRecord.field(shape=max(1, self.count))
        if self.count:
            upload_fields([(self.table, arrays)])
        self.textures = textures or TextureTable(None, [])
        # Rough plastics' coating transmittance tables, one row each (only where a scene has them).
        self.plastic_transmittance = None
        self.has_plastic_tables = bool(rows.plastic_tables)
        if rows.plastic_tables:
            tables = np.stack(rows.plastic_tables).astype(np.float32)
            self.plastic_transmittance = ti.field(ti.f32, shape=tables.shape)
            self.plastic_transmittance.from_numpy(tables)
        self._ggx_albedo = None
        self._dielectric_albedo = None
        self._sheen_albedo = None

    def update(self, rows: MaterialRows, arrays: dict) -> bool:
        """Upload edited rows (`arrays`: rows.arrays()) in place: True where they fit the table as
        built (as many rows and rough-plastic tables); False, changing nothing, where they do not."""
        if len(arrays["kind"]) != self.count or len(rows.plastic_tables) != (
                0 if self.plastic_transmittance is None else self.plastic_transmittance.shape[0]):
            return False
        if self.count:
            upload_fields([(self.table, arrays)])
        if rows.plastic_tables:
            self.plastic_transmittance.from_numpy(np.stack(rows.plastic_tables).astype(np.float32))
        self.arrays = arrays
        return True

    @property
    def ggx_albedo(self):
        """The GGX albedo table of the energy compensation, uploaded on first use (only kernels
        compiled with compensation ask for it)."""
        if self._ggx_albedo is None:
            from renderer.materials.energy import GgxAlbedo

            self._ggx_albedo = GgxAlbedo()
        return self._ggx_albedo

    @property
    def dielectric_albedo(self):
        """The rough-dielectric energy tables (glass compensation, coat layering), uploaded on first
        use like ggx_albedo."""
        if self._dielectric_albedo is None:
            from renderer.materials.dielectric_energy import DielectricAlbedo

            self._dielectric_albedo = DielectricAlbedo()
        return self._dielectric_albedo

    @property
    def sheen_albedo(self):
        """The sheen lobe's albedo table (layering under a sheen), uploaded on first use."""
        if self._sheen_albedo is None:
            from renderer.materials.sheen import SheenAlbedo

            self._sheen_albedo = SheenAlbedo()
        return self._sheen_albedo

    @classmethod
    def from_specs(cls, specs, medium_names: tuple[str, ...] = ()):
        return cls(MaterialRows.of_specs(specs, medium_names))

"""What a scene calls for. Kernels are compiled per Features, so nothing unused is simulated.

Features names *kinds* (BSDF kinds and layers, texture use, primitive and operator kinds, environment
kind, lens model), never instances: adding a tenth sphere to a scene with spheres compiles nothing new.
Material kinds and layers are sets of registry names (renderer/materials/kinds.py), like the SDF
primitive kinds: code asks `features.has_kind("dielectric")` inside `ti.static`.
"""
from __future__ import annotations

from dataclasses import dataclass, fields, replace

from renderer.geometry.mesh_data import KINDS as MESH_PRIMITIVES
from renderer.materials.kinds import KIND_NAMES, LAYER_NAMES, always_compensated, compensated_when_rough, kind
from renderer.scene.description import LIGHT_KINDS, SDF_OPERATORS, SDF_PRIMITIVES, Scene


@dataclass(frozen=True)
class Features:
    geometry: str = "sdf"
    material_kinds: frozenset = frozenset()  # names of the BSDF kinds used (null: invisible boundaries)
    material_layers: frozenset = frozenset()  # the principled layers used: clearcoat, sheen, specular
    has_emission: bool = False
    has_textures: bool = False
    has_normal_maps: bool = False  # glTF tangent-space normal maps
    # Mitsuba's normalmap and bumpmap: shading frames perturbed in the frame of the surface's texture
    # parametrisation, with the shadow-terminator term; bump maps add the height texture's gradient.
    has_mapped_frames: bool = False
    has_bump_maps: bool = False
    has_anisotropy: bool = False  # anisotropic microfacet widths, oriented along the surface's dp/du
    has_mixes: bool = False  # mixes of two materials, one chosen per shading point (Mitsuba's blendbsdf)
    # Kulla-Conty multiple scattering: rough GGX reflection (conductors, principled metal), rough
    # dielectric interfaces (glass, principled glass) and the principled coat's layering
    energy_compensation: bool = False
    has_media: bool = False  # participating media: free-flight sampling, phase functions, transmittance
    has_grid_media: bool = False  # media on 3D grids (with has_media): delta and ratio tracking
    analytic_fog: bool = False  # the exponential-blend approximation on camera rays
    has_dispersion: bool = False  # dispersive dielectrics: spectral paths (one wavelength per path)
    has_alpha: bool = False  # glTF MASK / BLEND coverage (and OBJ dissolve), tested in traversal
    has_vertex_colors: bool = False  # per-vertex colours multiplying the base colour
    has_instances: bool = False  # meshes placed many times, one copy of their triangles
    # Spheres or quads whose normals are turned over (Mitsuba's flip_normals): the mesh geometry
    # compiles in a sign per analytic primitive (MeshGeometry.has_flipped, from its data). Like
    # mesh_primitives, a description of the scene's geometry: with_everything() keeps it as it is.
    has_flipped_normals: bool = False
    has_thin: bool = False  # thin-walled transmission (glTF transmission without a volume)
    has_microfacet_models: bool = False  # rows whose microfacet model is not GGX (Beckmann, separable masking)
    has_sidedness: bool = False  # one-sided materials (a black back face)
    environment: str = "sky"  # "map" | "sky" | "constant"
    # The map or sky turned otherwise than about +y: lookups and sampling go through a 3x3 matrix (a
    # turn about +y is an azimuth offset, data). Like `environment`, a description of the scene.
    environment_rotated: bool = False
    depth_of_field: bool = False
    # Parallel camera rays (an orthographic camera): like the environment, a description of the
    # scene's camera rather than an optional effect; with_everything() keeps it as it is.
    orthographic: bool = False
    sdf_primitives: frozenset = frozenset()
    sdf_operators: frozenset = frozenset()
    mesh_primitives: frozenset = frozenset()
    # Kinds of the scene's lights without a surface (point, spot, directional): light sampling
    # compiles each kind's code only where the scene has one. Like `environment`, they describe the
    # scene rather than an optional effect: with_everything() keeps them as they are.
    light_kinds: frozenset = frozenset()
    has_light_textures: bool = False  # a spot's projected texture or a projector's image
    pixel_filter: tuple = ("box",)  # renderer/film/pixel_filter.py filter_key: compiled in

    def has_kind(self, name: str) -> bool:
        """Whether material kind `name` is compiled in (a registry name)."""
        return name in self.material_kinds

    def has_layer(self, name: str) -> bool:
        """Whether the principled layer `name` is compiled in (a registry name)."""
        return name in self.material_layers

    def has_light(self, kind: str) -> bool:
        """Whether light kind `kind` (one of LIGHT_KINDS) is compiled in."""
        return kind in self.light_kinds

    @property
    def has_delta_lights(self) -> bool:
        return bool(self.light_kinds)

    def active_effects(self) -> list[str]:
        """Short names for the HUD and `app.py info`."""
        flags = (*((kind(k).label, True) for k in KIND_NAMES if k in self.material_kinds),
                 ("emission", self.has_emission),
                 ("textures", self.has_textures), ("normal maps", self.has_normal_maps),
                 ("mapped frames", self.has_mapped_frames), ("bump maps", self.has_bump_maps),
                 ("anisotropy", self.has_anisotropy), ("mixes", self.has_mixes),
                 ("multiple scattering", self.energy_compensation),
                 ("media", self.has_media), ("grid media", self.has_grid_media), ("analytic fog", self.analytic_fog),
                 ("dispersion", self.has_dispersion), ("alpha", self.has_alpha),
                 ("vertex colours", self.has_vertex_colors), ("instances", self.has_instances),
                 ("flipped normals", self.has_flipped_normals),
                 ("thin walls", self.has_thin), ("microfacet models", self.has_microfacet_models),
                 ("one-sided", self.has_sidedness),
                 *((layer, True) for layer in LAYER_NAMES if layer in self.material_layers),
                 ("depth of field", self.depth_of_field), ("orthographic", self.orthographic),
                 *((f"{k} lights", True) for k in LIGHT_KINDS if k in self.light_kinds),
                 ("projected images", self.has_light_textures),
                 (f"{self.pixel_filter[0]} filter", self.pixel_filter[0] != "box"))
        names = [name for name, on in flags if on]
        names.append(f"env:{self.environment}" + (" rotated" if self.environment_rotated else ""))
        return names

    def describe(self) -> dict:
        out = {}
        for f in fields(self):
            v = getattr(self, f.name)
            out[f.name] = sorted(v) if isinstance(v, frozenset) else v
        return out

    def with_everything(self) -> "Features":
        """Every optional effect of this geometry kind switched on (for the cost benchmark)."""
        sdf = self.geometry == "sdf"
        return replace(self, material_kinds=frozenset(KIND_NAMES), material_layers=frozenset(LAYER_NAMES),
                       has_emission=True, has_textures=not sdf, has_normal_maps=not sdf,
                       has_mapped_frames=not sdf, has_bump_maps=not sdf, has_anisotropy=not sdf, has_mixes=not sdf,
                       depth_of_field=True,
                       energy_compensation=True, has_media=True, has_grid_media=True, analytic_fog=True,
                       has_dispersion=True, has_thin=True, has_microfacet_models=True, has_sidedness=True,
                       has_alpha=not sdf, has_vertex_colors=not sdf, has_instances=not sdf,
                       sdf_primitives=frozenset(SDF_PRIMITIVES) if sdf else frozenset(),
                       sdf_operators=frozenset(SDF_OPERATORS) if sdf else frozenset(),
                       mesh_primitives=frozenset() if sdf else frozenset(MESH_PRIMITIVES))

    def optional_effects(self) -> list[str]:
        """What with_everything() adds one by one (for the cost benchmark): boolean fields off
        here by field name, then material kinds and layers not used here by registry name."""
        every = self.with_everything()
        flags = [f.name for f in fields(self) if isinstance(getattr(self, f.name), bool)
                 and not getattr(self, f.name) and getattr(every, f.name)]
        return (flags + [k for k in KIND_NAMES if k not in self.material_kinds]
                + [layer for layer in LAYER_NAMES if layer not in self.material_layers])

    def with_effect(self, effect: str) -> "Features":
        """This plus one effect of optional_effects()."""
        if effect in KIND_NAMES:
            return replace(self, material_kinds=self.material_kinds | {effect})
        if effect in LAYER_NAMES:
            return replace(self, material_layers=self.material_layers | {effect})
        return replace(self, **{effect: True})


def features_from(geometry: str, material_uses: dict, environment: str, aperture: float,
                  sdf_nodes=(), mesh_kinds=frozenset(), energy_compensation: bool = True,
                  fog: str = "none", vertex_colors: bool = False, instances: bool = False,
                  light_kinds=frozenset(), pixel_filter: tuple = ("box",), orthographic: bool = False,
                  light_textures: bool = False, environment_rotated: bool = False,
                  flipped_normals: bool = False) -> Features:
    """material_uses: {"kinds", "layers": sets of registry names, "textures", "normal_maps",
    "mapped_frames", "bump_maps" (renderer/materials/mapped_frame_rows.py), "emission",
    "media": bool, "grid_media": whether one of them lies on a grid (`scene_grid_media`), "rough":
    whether a kind compensated where rough (conductor, dielectric) has roughness > 0}.
    energy_compensation: the scene's wish; compiled in only where such a rough material occurs, or
    a kind always compensated (principled, whose coat layering it also provides).
    fog: the scene's fog model ("none", "medium" or "analytic").
    vertex_colors, instances: whether the mesh data carries vertex colours / instanced meshes.
    light_kinds: the kinds of the scene's point, spot and directional lights (`scene_light_kinds`).
    light_textures: whether one of them projects an image (`scene_light_textures`).
    environment_rotated: whether the environment needs its full rotation (EnvironmentSpec.needs_matrix).
    flipped_normals: whether a sphere or quad of the mesh data has its normal turned over.
    orthographic: whether the camera's projection is orthographic."""
    kinds = material_uses["kinds"]
    layers = material_uses.get("layers", set())
    unknown = (set(kinds) - set(KIND_NAMES)) | (set(layers) - set(LAYER_NAMES))
    if unknown:
        raise ValueError(f"unknown material kinds or layers {sorted(unknown)}")
    return Features(
        geometry=geometry,
        material_kinds=frozenset(kinds),
        material_layers=frozenset(layers),
        has_emission=material_uses["emission"],
        has_textures=material_uses["textures"],
        has_normal_maps=material_uses["normal_maps"],
        has_mapped_frames=bool(material_uses.get("mapped_frames", False)),
        has_bump_maps=bool(material_uses.get("bump_maps", False)),
        has_anisotropy=bool(material_uses.get("anisotropy", False)),
        has_mixes=bool(material_uses.get("mixes", False)),
        energy_compensation=energy_compensation and (any(always_compensated(k) for k in kinds)
                                                     or material_uses.get("rough", True)),
        has_media=fog == "medium" or bool(material_uses.get("media", False)),
        has_grid_media=bool(material_uses.get("grid_media", False)),
        analytic_fog=fog == "analytic",
        has_dispersion=bool(material_uses.get("dispersion", False)),
        has_alpha=bool(material_uses.get("alpha", False)),
        has_vertex_colors=vertex_colors,
        has_instances=instances,
        has_flipped_normals=flipped_normals,
        has_thin=bool(material_uses.get("thin", False)),
        has_microfacet_models=bool(material_uses.get("microfacet_models", False)),
        has_sidedness=bool(material_uses.get("sidedness", False)),
        environment=environment,
        environment_rotated=environment_rotated,
        depth_of_field=aperture > 0.0,
        orthographic=orthographic,
        sdf_primitives=frozenset(n.kind for n in sdf_nodes if n.kind in SDF_PRIMITIVES),
        sdf_operators=frozenset(n.kind for n in sdf_nodes if n.kind in SDF_OPERATORS),
        mesh_primitives=frozenset(mesh_kinds),
        light_kinds=frozenset(light_kinds),
        has_light_textures=light_textures,
        pixel_filter=tuple(pixel_filter),
    )


def scene_pixel_filter(scene: Scene) -> tuple:
    """The scene's pixel filter as kernels compile it in."""
    from renderer.film.filter_keys import filter_key

    r = scene.render
    return filter_key(r.pixel_filter, r.filter_stddev, r.filter_radius)


def scene_light_kinds(scene: Scene) -> frozenset:
    """The kinds of the scene's lights without a surface."""
    return frozenset(light.kind for light in scene.lights)


def scene_light_textures(scene: Scene) -> bool:
    """Whether a spot or projector of the scene projects an image."""
    return any(light.texture is not None and light.kind in ("spot", "projector") for light in scene.lights)


def scene_grid_media(scene: Scene) -> bool:
    """Whether a medium that the scene's materials or its fog name lies on a grid."""
    named = {m.medium for m in scene.materials} | ({scene.fog.medium} if scene.fog.model == "medium" else set())
    return any(m.kind == "grid" and m.name in named for m in scene.media)


def scene_features(scene: Scene, aperture: float | None = None) -> Features:
    """Features of an SDF scene from its description alone (mesh scenes need their files loaded:
    the Renderer computes theirs from the assembled data)."""
    used_materials = {n.material for n in scene.sdf_objects}
    used = [m for m in scene.materials if m.name in used_materials] or list(scene.materials)
    nodes = [node for top in scene.sdf_objects for node in top.walk()]
    uses = {"kinds": {m.kind for m in used}, "textures": False, "normal_maps": False,
            "emission": any(m.is_emissive for m in used), "media": any(m.medium or m.outside_medium for m in used),
            "grid_media": scene_grid_media(scene),
            "dispersion": any(m.is_dispersive for m in used),
            "microfacet_models": any(m.microfacet != "ggx" for m in used),
            "sidedness": any(m.sidedness == "back_black" for m in used),
            "thin": any(m.thin and m.kind in ("dielectric", "principled", "disney") for m in used),
            "rough": any(compensated_when_rough(m.kind) and m.roughness > 0.0 for m in used)}
    lens = scene.camera.aperture if aperture is None else aperture
    return features_from(scene.geometry, uses, scene.environment.kind, lens, sdf_nodes=nodes,
                         energy_compensation=scene.render.energy_compensation, fog=scene.fog.model,
                         light_kinds=scene_light_kinds(scene), pixel_filter=scene_pixel_filter(scene),
                         orthographic=scene.camera.projection == "orthographic",
                         light_textures=scene_light_textures(scene),
                         environment_rotated=scene.environment.needs_matrix)

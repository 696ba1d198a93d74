"""Mitsuba 3 plugins (plugins.py) made into Lantern's plain scene description.

Each plugin maps onto a registered kind: sensors onto the camera, films and samplers onto the render
settings, BSDFs onto material rows, shapes onto mesh objects, emitters onto emissive materials, the
environment or lights (point, spot, directional). What has no counterpart yet is left out with one
warning naming file, line and plugin (MitsubaSceneWarning); so is every parameter a plugin was
given that nothing read.
docs/scene-format.md ("Mitsuba 3 scenes") lists the mapping.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from renderer.materials.metals import metal_names
from renderer.scene.description import (CameraSpec, EnvironmentSpec, LightSpec, MaterialSpec, MediumSpec,
                                        MeshObject, RenderSettings, Scene, TextureSpec)
from renderer.scene.errors import SceneError
from renderer.scene.mitsuba.ior_names import IOR_NAMES
from renderer.scene.mitsuba.plugins import Plugin, Rgb, Spectrum
from renderer.scene.mitsuba.xml_document import Resolution
from renderer.scene.model_files import ModelFiles
from renderer.scene.references import missing_file_problem
from renderer.spectral.mitsuba_rgb import spectrum_to_rgb

MESH_FILE_TYPES = ("obj", "ply")
PATH_INTEGRATORS = ("path", "volpath", "volpathmis", "ptracer", "direct")  # all estimate the same image
SAMPLERS = {"independent": "independent", "stratified": "sobol", "multijitter": "sobol", "orthogonal": "sobol",
            "ldsampler": "sobol"}
# Parameters of Mitsuba's principled (Disney) BSDF that Lantern's glTF principled shapes otherwise.
DISNEY_ONLY = ("anisotropic", "clearcoat", "clearcoat_gloss", "sheen", "sheen_tint", "specular_tint",
               "spec_tint", "specular")
FILM_DEFAULT_SIZE = (768, 576)  # Mitsuba's hdrfilm
DEFAULT_SPP = 4  # Mitsuba's samplers
DEFAULT_FOCAL_LENGTH = "50mm"  # Mitsuba's perspective sensor without fov or focal_length
FILM_DIAGONAL_MM = math.hypot(36.0, 24.0)  # focal_length converts against 35 mm film's diagonal
DEFAULT_REFLECTANCE = (0.5, 0.5, 0.5)  # Mitsuba's diffuse
# Lantern's local frame for quads and discs lies in xz and faces +y; Mitsuba's rectangle and disk lie
# in xy and face +z. This rotation takes local z to x, x to y and y (the normal) to z, so a quad's
# edge parameters (along its local z, then x) are the rectangle's texture coordinates (u, v).
XZ_TO_XY = np.array([[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
# Mitsuba's cube is [-1, 1]^3: six unit-square faces, each a rectangle moved out along its normal.
CUBE_FACES = tuple(
    np.array(f, np.float64) for f in (
        [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]],  # +z
        [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, -1], [0, 0, 0, 1]],  # -z
        [[0, 0, 1, 1], [0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 0, 1]],  # +x
        [[0, 0, -1, -1], [0, 1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 1]],  # -x
        [[1, 0, 0, 0], [0, 0, 1, 1], [0, -1, 0, 0], [0, 0, 0, 1]],  # +y
        [[1, 0, 0, 0], [0, 0, -1, -1], [0, 1, 0, 0], [0, 0, 0, 1]],  # -y
    ))
# Parameters that change nothing Lantern computes (output formats, clipping planes far from any
# geometry a test scene has): read without a warning.
QUIET = {"film": ("pixel_format", "component_format", "rfilter", "banner", "file_format", "sample_border"),
         "sensor": ("near_clip", "far_clip"), "integrator": ("hide_emitters",)}


class MitsubaSceneWarning(UserWarning):
    """Something a Mitsuba scene asks for that Lantern leaves out or approximates."""


def warn(plugin: Plugin, message: str) -> None:
    warnings.warn(f"{plugin.where()}: {plugin.label()}: {message}", MitsubaSceneWarning, stacklevel=3)


def leave_out(plugin: Plugin, message: str) -> None:
    """One warning for a plugin left out whole (its parameters are not listed one by one)."""
    plugin.used.update(plugin.properties)
    warn(plugin, message)


def build_scene(root: Plugin, path: Path, resolution: Resolution, model_files: ModelFiles,
                defines: dict[str, str] | None = None) -> Scene:
    return _Builder(root, path, resolution, model_files, dict(defines or {})).scene()


class _Builder:
    def __init__(self, root: Plugin, path: Path, resolution: Resolution, model_files: ModelFiles,
                 defines: dict[str, str]):
        self.root, self.path, self.resolution, self.model_files = root, path, resolution, model_files
        self.defines = defines
        self.materials: list[MaterialSpec] = []
        self.material_of: dict[int, str] = {}  # id(bsdf plugin) -> its material name
        self.media: list[MediumSpec] = []
        self.medium_of: dict[int, str] = {}  # id(medium plugin) -> its medium name
        self.objects: list[MeshObject] = []
        self.lights: list[LightSpec] = []
        self.visited: list[Plugin] = []

    # --- the scene ----------------------------------------------------------------------------

    def scene(self) -> Scene:
        sensors = self.root.objects("sensor")
        camera, render = self.sensor(sensors[0]) if sensors else (CameraSpec(), RenderSettings(*FILM_DEFAULT_SIZE))
        for extra in sensors[1:]:
            warn(extra, "a second sensor is left out (Lantern renders the first)")
        render = self.integrator(render)
        environment = self.environment()
        for shape in self.root.objects("shape"):
            self.shape(shape)
        for kind in ("bsdf", "texture", "medium"):  # declarations: used where a <ref> names them
            for plugin in self.root.objects(kind):
                if id(plugin) not in self.material_of and plugin.id is None:
                    warn(plugin, f"a <{kind}> outside any shape is used by nothing")
        if not self.objects:
            raise SceneError(self.path, "nothing Lantern can render: the scene has no shape it supports")
        self.warn_unused()
        return Scene(name=self.path.stem, path=self.path, geometry="mesh", camera=camera, render=render,
                     environment=environment, materials=tuple(self.materials), mesh_objects=tuple(self.objects),
                     media=tuple(self.media), source_files=tuple(self.resolution.read),
                     parameters=tuple(sorted(self.defines.items())), lights=tuple(self.lights),
                     description=f"Mitsuba 3 scene {self.path.name}", model_files=self.model_files)

    def visit(self, plugin: Plugin) -> Plugin:
        self.visited.append(plugin)
        return plugin

    def warn_unused(self) -> None:
        seen = set()
        for plugin in self.visited:
            if id(plugin) in seen:
                continue
            seen.add(id(plugin))
            quiet = QUIET.get(plugin.kind, ())
            for name, value in plugin.properties.items():
                if name in plugin.used or name in quiet or isinstance(value, Plugin) and value.kind == "texture":
                    continue
                warn(plugin, f"parameter '{name}' is not supported and was ignored")

    # --- sensor, film, sampler, integrator ------------------------------------------------------

    def sensor(self, sensor: Plugin) -> tuple[CameraSpec, RenderSettings]:
        self.visit(sensor)
        if sensor.type not in ("perspective", "thinlens"):
            warn(sensor, "rendered as a perspective camera (only perspective and thinlens are supported)")
        films = sensor.objects("film")
        width, height = FILM_DEFAULT_SIZE
        pixel_filter, radius, stddev = "gaussian", 1.0, 0.5  # Mitsuba's film without an rfilter
        if films:
            film = self.visit(films[0])
            if film.type != "hdrfilm":
                warn(film, "read as an hdrfilm")
            width, height = film.integer("width", width), film.integer("height", height)
            if width < 1 or height < 1:
                raise film.error(f"a {width}x{height} image has no pixels")
            for crop in ("crop_offset_x", "crop_offset_y", "crop_width", "crop_height"):
                if film.has(crop):
                    warn(film, f"'{crop}' is not supported: the whole image is rendered")
                    film.used.add(crop)
            filters = film.objects("rfilter")
            pixel_filter = filters[0].type if filters else "gaussian"  # Mitsuba's default filter
            if filters:
                rfilter = self.visit(filters[0])
                radius = rfilter.number("radius", 1.0) if pixel_filter == "tent" else 1.0
                stddev = rfilter.number("stddev", 0.5) if pixel_filter == "gaussian" else 0.5
            if pixel_filter not in ("box", "tent", "gaussian"):
                warn(filters[0], f"the {pixel_filter} reconstruction filter is rendered with the box filter")
                pixel_filter = "box"
            if radius <= 0 or stddev <= 0:
                raise film.error("a reconstruction filter's radius and stddev must be positive")
        spp, sampler = DEFAULT_SPP, "independent"
        samplers = sensor.objects("sampler")
        if samplers:
            sampler_plugin = self.visit(samplers[0])
            spp = sampler_plugin.integer("sample_count", DEFAULT_SPP)
            sampler = SAMPLERS.get(sampler_plugin.type, "independent")
            if sampler_plugin.type not in SAMPLERS:
                warn(sampler_plugin, "rendered with the independent sampler")
            sampler_plugin.used.update(("seed", "jitter", "scramble_seed"))
        if spp < 1:
            raise sensor.error(f"sample_count {spp}: at least one sample per pixel")
        matrix = sensor.transform()
        position = matrix[:3, 3]
        forward, up = matrix[:3, 2], matrix[:3, 1]
        if np.linalg.det(matrix[:3, :3]) < 0:
            warn(sensor, "its to_world mirrors the image, which Lantern's camera does not: rendered unmirrored")
        aperture, focus = 0.0, 5.0
        if sensor.type == "thinlens":
            aperture = sensor.number("aperture_radius", 0.03)
            focus = sensor.number("focus_distance", 0.0) or float(np.linalg.norm(forward))
        camera = CameraSpec(position=_vec(position), look_at=_vec(position + forward / np.linalg.norm(forward)),
                            up=_vec(up / np.linalg.norm(up)), fov=self.vertical_fov(sensor, width, height),
                            aperture=aperture, focus_distance=focus)
        return camera, RenderSettings(width=width, height=height, spp=spp, sampler=sampler, pixel_filter=pixel_filter,
                                      filter_radius=radius, filter_stddev=stddev)

    @staticmethod
    def vertical_fov(sensor: Plugin, width: int, height: int) -> float:
        """Lantern's vertical field of view for Mitsuba's fov along fov_axis (or focal_length)."""
        if sensor.has("fov") and sensor.has("focal_length"):
            raise sensor.error("give fov or focal_length, not both")
        if not sensor.has("fov"):
            text = sensor.text("focal_length", DEFAULT_FOCAL_LENGTH)
            try:
                mm = float(text.lower().removesuffix("mm"))
            except ValueError:
                raise sensor.error(f"focal_length '{text}' is not a length in mm") from None
            fov, axis = math.degrees(2.0 * math.atan(FILM_DIAGONAL_MM / (2.0 * mm))), "diagonal"
        else:
            fov, axis = sensor.number("fov", 0.0), sensor.text("fov_axis", "x").lower()
        if not 0.0 < fov < 180.0:
            raise sensor.error(f"fov {fov:g} is not between 0 and 180 degrees")
        if axis == "smaller":
            axis = "x" if width < height else "y"
        elif axis == "larger":
            axis = "x" if width > height else "y"
        extent = {"x": width, "y": height, "diagonal": math.hypot(width, height)}.get(axis)
        if extent is None:
            raise sensor.error(f"fov_axis '{axis}' (x, y, diagonal, smaller or larger)")
        half = math.tan(math.radians(fov) / 2.0) * height / extent
        return math.degrees(2.0 * math.atan(half))

    def integrator(self, render: RenderSettings) -> RenderSettings:
        integrators = self.root.objects("integrator")
        if not integrators:
            return replace(render, integrator="mis", max_depth=-1)  # Mitsuba's default: path, unlimited
        plugin = self.visit(integrators[0])
        while plugin.type == "moment":  # its extra outputs aside, the image is its nested integrator's
            nested = plugin.objects("integrator")
            if not nested:
                raise plugin.error("needs a nested <integrator>")
            plugin = self.visit(nested[0])
        if plugin.type in PATH_INTEGRATORS:
            default_depth = 2 if plugin.type == "direct" else -1
            depth = plugin.integer("max_depth", default_depth)
            if depth == 0 or depth < -1:
                raise plugin.error(f"max_depth {depth}: 1 or more, or -1 for unlimited")
            plugin.used.update(("rr_depth", "emitter_samples", "bsdf_samples", "samples_per_pass"))
            return replace(render, integrator="mis", max_depth=depth)
        if plugin.type in ("depth", "aov"):
            return replace(render, integrator="depth", max_depth=1)
        warn(plugin, "rendered with Lantern's path tracer (mis)")
        return replace(render, integrator="mis", max_depth=-1)

    # --- emitters -------------------------------------------------------------------------------

    def environment(self) -> EnvironmentSpec:
        chosen = None
        for emitter in self.root.objects("emitter"):
            self.visit(emitter)
            if emitter.type in ("constant", "envmap"):
                if chosen is not None:
                    warn(emitter, "a second environment emitter is left out (Lantern has one environment)")
                    continue
                chosen = self.constant(emitter) if emitter.type == "constant" else self.envmap(emitter)
            elif emitter.type in ("point", "spot", "directional"):
                self.lights.append(self.light(emitter))
            else:
                leave_out(emitter, "this emitter type is not supported yet and is left out")
        return chosen or EnvironmentSpec(kind="constant", color=(0.0, 0.0, 0.0))

    def light(self, emitter: Plugin) -> LightSpec:
        """A point, spot or directional emitter (Mitsuba's local frame: a spot shines along +z, a
        directional light travels along +z)."""
        t = emitter.type
        if t == "directional":
            irradiance = self.colour(emitter, "irradiance", (1.0, 1.0, 1.0), emitter=True)
            return LightSpec("directional", direction=self.frame_vector(emitter, "direction"), irradiance=irradiance)
        intensity = self.colour(emitter, "intensity", (1.0, 1.0, 1.0), emitter=True)
        if t == "point":
            return LightSpec("point", position=self.light_position(emitter), intensity=intensity)
        if emitter.has("texture"):
            warn(emitter, "a spot's projected texture is not supported yet: ignored (the spot is untextured)")
            emitter.used.add("texture")
        cutoff = emitter.number("cutoff_angle", 20.0)
        beam = emitter.number("beam_width", 0.75 * cutoff)
        if not 0.0 < cutoff < 180.0:
            raise emitter.error(f"cutoff_angle {cutoff:g} is not between 0 and 180 degrees")
        if not 0.0 <= beam <= cutoff:
            raise emitter.error(f"beam_width {beam:g} is not between 0 and cutoff_angle {cutoff:g}")
        matrix = emitter.transform()
        columns = matrix[:3, :3] / np.linalg.norm(matrix[:3, :3], axis=0)
        if not np.allclose(columns.T @ columns, np.eye(3), atol=1e-5):
            warn(emitter, "its to_world scales unevenly or shears, which would make the cone elliptical: "
                          "the cone is kept round about its axis")
        return LightSpec("spot", position=_vec(matrix[:3, 3]), direction=self.frame_vector(emitter, None),
                         intensity=intensity, cutoff_angle=cutoff, beam_width=beam)

    @staticmethod
    def light_position(emitter: Plugin) -> tuple:
        """A light's `position`, else its to_world's origin (not both, as in Mitsuba)."""
        if emitter.has("position"):
            if emitter.has("to_world"):
                raise emitter.error("give position or to_world, not both")
            return _vec(_triple(emitter, "position"))
        return _vec(emitter.transform()[:3, 3])

    @staticmethod
    def frame_vector(emitter: Plugin, name: str | None) -> tuple:
        """The unit direction of the light's local +z: the vector parameter `name` where given
        (not with to_world, as in Mitsuba), else its to_world's."""
        if name is not None and emitter.has(name):
            if emitter.has("to_world"):
                raise emitter.error(f"give {name} or to_world, not both")
            v = np.asarray(_triple(emitter, name), np.float64)
        else:
            v = emitter.transform()[:3, :3] @ np.array([0.0, 0.0, 1.0])
        length = float(np.linalg.norm(v))
        if not np.isfinite(length) or length == 0.0:
            raise emitter.error(f"its {name or 'to_world'} gives no direction (a zero vector)")
        return _vec(v / length)

    def constant(self, emitter: Plugin) -> EnvironmentSpec:
        return EnvironmentSpec(kind="constant", color=self.colour(emitter, "radiance", (1.0, 1.0, 1.0), emitter=True))

    def envmap(self, emitter: Plugin) -> EnvironmentSpec:
        name = emitter.text("filename")
        if name is None:
            raise emitter.error("needs a filename")
        file = self.find(emitter, name)
        rotation = emitter.transform()[:3, :3]
        angle = math.degrees(math.atan2(rotation[0, 2], rotation[0, 0]))
        c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
        about_y = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        if not np.allclose(rotation, about_y, atol=1e-6):
            warn(emitter, "its to_world is more than a rotation about +y, which Lantern's environment supports: "
                          "only that part is kept")
        return EnvironmentSpec(kind="map", file=file, intensity=emitter.number("scale", 1.0), rotation=angle)

    # --- shapes ---------------------------------------------------------------------------------

    def shape(self, shape: Plugin) -> None:
        self.visit(shape)
        material = self.shape_material(shape)
        matrix = shape.transform()
        if shape.type in MESH_FILE_TYPES:
            name = shape.text("filename")
            if name is None:
                raise shape.error("needs a filename")
            shape.used.update(("face_normals", "flip_tex_coords", "flip_normals"))
            if shape.get("face_normals", False):
                warn(shape, "face_normals: the file's vertex normals are used")
            self.add(MeshObject(kind="mesh", file=self.find(shape, name), material=material), matrix, shape)
        elif shape.type == "sphere":
            centre = np.array(shape.get("center", (0.0, 0.0, 0.0)), np.float64)
            radius = shape.number("radius", 1.0)
            scales = np.linalg.norm(matrix[:3, :3], axis=0)
            if not np.allclose(scales, scales[0], rtol=1e-5):
                raise shape.error("a sphere's to_world must scale uniformly")
            placed = matrix @ _translation(centre)
            self.add(MeshObject(kind="sphere", radius=radius, material=material), placed, shape)
        elif shape.type == "rectangle":
            self.add(MeshObject(kind="quad", size=(2.0, 2.0), material=material), matrix @ XZ_TO_XY, shape)
        elif shape.type == "disk":
            self.add(MeshObject(kind="disc", radius=1.0, material=material), matrix @ XZ_TO_XY, shape)
        elif shape.type == "cube":
            for face in CUBE_FACES:
                self.add(MeshObject(kind="quad", size=(2.0, 2.0), material=material), matrix @ face @ XZ_TO_XY, shape)
        else:
            leave_out(shape, "this shape type is not supported yet and is left out")

    def add(self, obj: MeshObject, matrix: np.ndarray, shape: Plugin) -> None:
        if not np.all(np.isfinite(matrix)) or abs(np.linalg.det(matrix[:3, :3])) < 1e-30:
            raise shape.error("its to_world is singular")
        self.objects.append(replace(obj, to_world=tuple(tuple(float(x) for x in row) for row in matrix)))

    def shape_material(self, shape: Plugin) -> str:
        bsdfs = shape.objects("bsdf")
        bsdf = bsdfs[0] if bsdfs else None
        emitters = shape.objects("emitter")
        emission = (0.0, 0.0, 0.0)
        if emitters:
            emitter = self.visit(emitters[0])
            if emitter.type != "area":
                leave_out(emitter, "only area emitters can sit on a shape: left out")
            else:
                emission = self.colour(emitter, "radiance", (1.0, 1.0, 1.0), emitter=True)
        base = self.material(bsdf) if bsdf is not None else self.default_material()
        medium = self.interior(shape)
        if max(emission) <= 0.0 and not medium:
            return base.name
        suffix = "+".join(part for part in ("emitter" if max(emission) > 0.0 else "", medium) if part)
        name = f"{base.name}+{suffix}"
        taken = {m.name for m in self.materials}
        if name in taken:
            name = next(f"{name}#{k}" for k in range(2, len(taken) + 2) if f"{name}#{k}" not in taken)
        self.materials.append(replace(base, name=name, emission=emission, medium=medium))
        return name

    def interior(self, shape: Plugin) -> str:
        """The name of the homogeneous medium inside a shape ("" for none)."""
        if shape.has("exterior"):
            warn(shape, "an exterior medium is not supported yet: the space outside is empty")
            shape.used.add("exterior")
        medium = shape.get("interior")
        if medium is None:
            return ""
        if not isinstance(medium, Plugin) or medium.kind != "medium":
            raise shape.error("'interior' must be a <medium>")
        if id(medium) not in self.medium_of:
            self.medium_of[id(medium)] = self.medium(self.visit(medium))
        return self.medium_of[id(medium)]

    def medium(self, medium: Plugin) -> str:
        if medium.type != "homogeneous":
            leave_out(medium, "only homogeneous media are supported yet: the shape is empty inside")
            return ""
        scale = medium.number("scale", 1.0)
        sigma_t = np.array(self.colour(medium, "sigma_t", (1.0, 1.0, 1.0), bounded=False)) * scale
        albedo = np.array(self.colour(medium, "albedo", (0.75, 0.75, 0.75)))
        g = 0.0
        phases = medium.objects("phase")
        if phases:
            phase = self.visit(phases[0])
            if phase.type == "hg":
                g = phase.number("g", 0.8)
            elif phase.type != "isotropic":
                warn(phase, "rendered as an isotropic phase function")
        medium.used.add("sample_emitters")
        name = medium.id or f"medium{len(self.media)}"
        self.media.append(MediumSpec(name, sigma_a=_vec(sigma_t * (1.0 - albedo)), sigma_s=_vec(sigma_t * albedo), g=g))
        return name

    def default_material(self) -> MaterialSpec:
        for m in self.materials:
            if m.name == "default":
                return m
        spec = MaterialSpec(name="default", kind="diffuse", base_color=DEFAULT_REFLECTANCE)
        self.materials.append(spec)
        return spec

    # --- BSDFs ----------------------------------------------------------------------------------

    def material(self, bsdf: Plugin) -> MaterialSpec:
        key = id(bsdf)
        if key in self.material_of:
            return next(m for m in self.materials if m.name == self.material_of[key])
        spec = self.bsdf(self.visit(bsdf))
        spec = replace(spec, name=bsdf.id or f"{bsdf.type}{len(self.materials)}")
        if any(m.name == spec.name for m in self.materials):
            spec = replace(spec, name=f"{spec.name}#{len(self.materials)}")
        self.materials.append(spec)
        self.material_of[key] = spec.name
        return spec

    def bsdf(self, bsdf: Plugin) -> MaterialSpec:
        t = bsdf.type
        if t == "twosided":  # Lantern's surfaces shade both sides alike
            return self.inner(bsdf)
        if t in ("bumpmap", "normalmap", "mask"):
            warn(bsdf, f"{t} is not supported yet: the BSDF inside it is used as it is")
            bsdf.used.update(("opacity",))
            return self.inner(bsdf)
        if t == "blendbsdf":
            warn(bsdf, "blendbsdf is not supported yet: its first BSDF is used")
            bsdf.used.add("weight")
            return self.inner(bsdf)
        if t == "diffuse":
            colour, texture = self.base_colour(bsdf, "reflectance", DEFAULT_REFLECTANCE)
            return MaterialSpec("", "diffuse", base_color=colour, base_color_texture=texture)
        if t in ("conductor", "roughconductor"):
            return self.conductor(bsdf)
        if t in ("dielectric", "roughdielectric", "thindielectric"):
            return MaterialSpec("", "dielectric", base_color=self.colour(bsdf, "specular_transmittance", (1.0,) * 3),
                                roughness=self.roughness(bsdf) if t == "roughdielectric" else 0.0,
                                ior=self.relative_ior(bsdf), thin=t == "thindielectric")
        if t in ("plastic", "roughplastic"):
            warn(bsdf, f"Mitsuba's {t} model is not supported yet: rendered as a principled dielectric "
                       "with its diffuse colour, roughness and index")
            bsdf.used.update(("nonlinear", "specular_reflectance"))
            colour, texture = self.base_colour(bsdf, "diffuse_reflectance", DEFAULT_REFLECTANCE)
            return MaterialSpec("", "principled", base_color=colour, base_color_texture=texture,
                                roughness=self.roughness(bsdf) if t == "roughplastic" else 0.0,
                                ior=self.relative_ior(bsdf, default_int=1.49))
        if t in ("principled", "principledthin"):
            return self.principled(bsdf)
        if t == "null":
            return MaterialSpec("", "null")
        warn(bsdf, "this BSDF type is not supported yet: rendered as Mitsuba's default diffuse")
        return MaterialSpec("", "diffuse", base_color=DEFAULT_REFLECTANCE)

    def inner(self, bsdf: Plugin) -> MaterialSpec:
        nested = bsdf.objects("bsdf")
        if not nested:
            raise bsdf.error("needs a nested <bsdf>")
        return self.bsdf(self.visit(nested[0]))

    def conductor(self, bsdf: Plugin) -> MaterialSpec:
        roughness = self.roughness(bsdf) if bsdf.type == "roughconductor" else 0.0
        tint = self.colour(bsdf, "specular_reflectance", (1.0, 1.0, 1.0))
        if bsdf.has("eta") or bsdf.has("k"):
            eta = self.colour(bsdf, "eta", (0.0, 0.0, 0.0), bounded=False)
            k = self.colour(bsdf, "k", (1.0, 1.0, 1.0), bounded=False)
            spec = MaterialSpec("", "conductor", roughness=roughness, eta=eta, k=k)
        else:
            name = bsdf.text("material", "none")
            if name == "none":  # Mitsuba's perfect mirror
                return MaterialSpec("", "conductor", base_color=tint, roughness=roughness, edge_tint=tint)
            known = {m.lower(): m for m in metal_names()}
            if name.lower() not in known:
                raise bsdf.error(f"unknown conductor material '{name}' (known: {', '.join(sorted(known.values()))})")
            spec = MaterialSpec("", "conductor", roughness=roughness, metal=known[name.lower()])
        if tint != (1.0, 1.0, 1.0):
            warn(bsdf, "specular_reflectance on a conductor with a complex index is not supported: ignored")
        return spec

    def roughness(self, bsdf: Plugin) -> float:
        """Lantern's perceptual roughness (alpha = roughness^2) from Mitsuba's alpha."""
        distribution = bsdf.text("distribution", "beckmann").lower()
        if distribution != "ggx":
            warn(bsdf, f"the {distribution} distribution is rendered as GGX with the same alpha")
        bsdf.used.add("sample_visible")
        if bsdf.has("alpha_u") or bsdf.has("alpha_v"):
            alpha_u, alpha_v = self.scalar(bsdf, "alpha_u", 0.1), self.scalar(bsdf, "alpha_v", 0.1)
            if alpha_u != alpha_v:
                warn(bsdf, "anisotropic roughness is not supported yet: rendered with the mean of alpha_u and alpha_v")
            alpha = 0.5 * (alpha_u + alpha_v)
        else:
            alpha = self.scalar(bsdf, "alpha", 0.1)
        if alpha < 0:
            raise bsdf.error(f"alpha {alpha:g} is negative")
        return min(1.0, math.sqrt(alpha))

    def relative_ior(self, bsdf: Plugin, default_int: float = 1.5046) -> float:
        interior = self.ior_value(bsdf, "int_ior", default_int)
        exterior = self.ior_value(bsdf, "ext_ior", IOR_NAMES["air"])
        return interior / exterior

    @staticmethod
    def ior_value(bsdf: Plugin, name: str, default: float) -> float:
        value = bsdf.get(name, default)
        if isinstance(value, str):
            if value.lower() not in IOR_NAMES:
                raise bsdf.error(f"unknown {name} '{value}' (known: {', '.join(IOR_NAMES)})")
            return IOR_NAMES[value.lower()]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or value <= 0:
            raise bsdf.error(f"{name} must be a positive number or a known name")
        return float(value)

    def principled(self, bsdf: Plugin) -> MaterialSpec:
        thin = bsdf.type == "principledthin"
        if thin:
            bsdf.used.update(("diff_trans", "flatness"))
        # Mitsuba's principled is Disney's model; Lantern's is glTF's. Base colour, roughness, metallic,
        # transmission and index mean the same in both; the other lobes are shaped differently.
        different = [name for name in DISNEY_ONLY if bsdf.has(name)]
        if different:
            warn(bsdf, f"{', '.join(different)}: Disney's lobes are not Lantern's (glTF) principled model; "
                       "left out")
            bsdf.used.update(different)
        colour, texture = self.base_colour(bsdf, "base_color", DEFAULT_REFLECTANCE)
        return MaterialSpec(
            "", "principled", base_color=colour, base_color_texture=texture,
            roughness=self.scalar(bsdf, "roughness", 0.5), metallic=self.scalar(bsdf, "metallic", 0.0),
            transmission=self.scalar(bsdf, "spec_trans", 0.0), ior=self.scalar(bsdf, "eta", 1.5), thin=thin)

    # --- values -----------------------------------------------------------------------------------

    def base_colour(self, plugin: Plugin, name: str, default) -> tuple[tuple, TextureSpec | None]:
        """A colour parameter that may hold a bitmap or checkerboard texture: (the colour the
        texture multiplies, the texture or None)."""
        value = plugin.properties.get(name)
        if isinstance(value, Plugin) and value.kind == "texture" and value.type in ("bitmap", "checkerboard"):
            plugin.used.add(name)
            return (1.0, 1.0, 1.0), self.texture(self.visit(value))
        return self.colour(plugin, name, default), None

    def texture(self, texture: Plugin) -> TextureSpec:
        matrix = texture.transform("to_uv")
        to_uv = tuple(tuple(float(matrix[r, c]) for c in (0, 1, 3)) for r in (0, 1)) + ((0.0, 0.0, 1.0),)
        if texture.type == "checkerboard":
            return TextureSpec("checkerboard", transform=to_uv, nearest=True,
                               color0=self.colour(texture, "color0", (0.4, 0.4, 0.4)),
                               color1=self.colour(texture, "color1", (0.2, 0.2, 0.2)))
        name = texture.text("filename")
        if name is None:
            raise texture.error("needs a filename")
        filter_type = texture.text("filter_type", "bilinear")
        wrap = texture.text("wrap_mode", "repeat")
        if filter_type not in ("bilinear", "nearest"):
            raise texture.error(f"filter_type '{filter_type}' (bilinear or nearest)")
        if wrap not in ("repeat", "mirror", "clamp"):
            raise texture.error(f"wrap_mode '{wrap}' (repeat, mirror or clamp)")
        texture.used.add("format")
        return TextureSpec("bitmap", file=self.find(texture, name), srgb=not texture.get("raw", False),
                           wrap=wrap, nearest=filter_type == "nearest", transform=to_uv)

    def scalar(self, plugin: Plugin, name: str, default: float) -> float:
        value = plugin.get(name, default)
        if isinstance(value, Plugin):
            warn(plugin, f"a <texture type=\"{value.type}\"> on '{name}' is not supported yet: {default:g} is used")
            return default
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise plugin.error(f"'{name}' must be a number")
        return float(value)

    def colour(self, plugin: Plugin, name: str, default, emitter: bool = False, bounded: bool = True) -> tuple:
        """An RGB parameter: a number, <rgb> or <spectrum> (made RGB as Mitsuba's RGB variants do:
        reflectances bounded and against D65, emission unbounded and without it)."""
        value = plugin.get(name, None)
        if value is None:
            return tuple(default)
        if isinstance(value, Plugin):
            if value.kind == "texture" and value.type == "bitmap":
                warn(plugin, f"bitmap textures are not supported on Mitsuba materials yet: '{name}' is "
                             f"{_rgb_text(default)}")
            else:
                warn(plugin, f"a <{value.kind} type=\"{value.type}\"> on '{name}' is not supported yet: "
                             f"{_rgb_text(default)} is used")
            return tuple(default)
        if isinstance(value, Rgb):
            return value.value
        if isinstance(value, Spectrum):
            if value.uniform is not None:
                return (value.uniform,) * 3
            unbounded = emitter or not bounded
            return spectrum_to_rgb(value.wavelengths, value.values, bounded=not unbounded, d65=not unbounded)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise plugin.error(f"'{name}' must be a colour (a number, <rgb> or <spectrum>)")
        return (float(value),) * 3

    def find(self, plugin: Plugin, name: str) -> Path:
        path = self.resolution.find(name, plugin.file)
        if not path.exists() or path.is_dir():
            raise plugin.error(f"{name}: {missing_file_problem(path)} (looked for {path})")
        return path


def _vec(v) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _triple(plugin: Plugin, name: str) -> tuple:
    value = plugin.get(name)
    if not (isinstance(value, tuple) and len(value) == 3):
        raise plugin.error(f"'{name}' must be a <point> or <vector>")
    return value


def _translation(offset) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = offset
    return m


def _rgb_text(rgb) -> str:
    return "(" + ", ".join(f"{c:g}" for c in rgb) + ")"

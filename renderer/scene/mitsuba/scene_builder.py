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
from dataclasses import replace
from pathlib import Path

import numpy as np

from renderer.scene.description import (CameraSpec, EnvironmentSpec, LightSpec, MaterialSpec, MediumSpec,
                                        MeshObject, RenderSettings, Scene, TextureSpec)
from renderer.scene.errors import SceneError
from renderer.scene.mitsuba.bsdfs import DEFAULT_REFLECTANCE, bsdf_spec
from renderer.scene.mitsuba.emitters import EmitterReader
from renderer.scene.mitsuba.mesh_attribute_textures import is_mesh_attribute, with_mesh_attribute
from renderer.scene.mitsuba.media import medium_spec
from renderer.scene.mitsuba.plugins import Plugin, Rgb, Spectrum
from renderer.scene.mitsuba.scene_warnings import leave_out, warn
from renderer.scene.mitsuba.shapes import ShapeReader
from renderer.scene.mitsuba.xml_document import Resolution
from renderer.scene.model_files import ModelFiles
from renderer.scene.references import missing_file_problem
from renderer.spectral.mitsuba_rgb import spectrum_to_rgb

PATH_INTEGRATORS = ("path", "volpath", "volpathmis", "ptracer", "direct")  # all estimate the same image
SAMPLERS = {"independent": "independent", "stratified": "sobol", "multijitter": "sobol", "orthogonal": "sobol",
            "ldsampler": "sobol"}
FILM_DEFAULT_SIZE = (768, 576)  # Mitsuba's hdrfilm
DEFAULT_SPP = 4  # Mitsuba's samplers
DEFAULT_FOCAL_LENGTH = "50mm"  # Mitsuba's perspective sensor without fov or focal_length
FILM_DIAGONAL_MM = math.hypot(36.0, 24.0)  # focal_length converts against 35 mm film's diagonal
# Parameters that change nothing Lantern computes (output formats, clipping planes far from any
# geometry a test scene has): read without a warning.
QUIET = {"film": ("pixel_format", "component_format", "rfilter", "banner", "file_format", "sample_border"),
         "sensor": ("near_clip", "far_clip"), "integrator": ("hide_emitters",)}


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
        # Mitsuba's rough BSDFs scatter once: its scenes render without Lantern's energy compensation.
        render = replace(render, energy_compensation=False)
        environment = self.environment()
        shapes = ShapeReader(self)  # shapes.py
        for shape in self.root.objects("shape"):
            shapes.read(shape)
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
        if sensor.type not in ("perspective", "thinlens", "orthographic"):
            warn(sensor, "rendered as a perspective camera (only perspective, thinlens and orthographic are "
                         "supported)")
        films = sensor.objects("film")
        width, height = FILM_DEFAULT_SIZE
        pixel_filter, radius, stddev = "gaussian", 1.0, 0.5  # Mitsuba's film without an rfilter
        crop = None
        if films:
            film = self.visit(films[0])
            if film.type != "hdrfilm":
                warn(film, "read as an hdrfilm")
            width, height = film.integer("width", width), film.integer("height", height)
            if width < 1 or height < 1:
                raise film.error(f"a {width}x{height} image has no pixels")
            crop = self.crop_window(film, width, height)
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
                            up=_vec(up / np.linalg.norm(up)), aperture=aperture, focus_distance=focus)
        if sensor.type == "orthographic":
            camera = replace(camera, projection="orthographic", ortho_height=self.ortho_height(sensor, width, height))
        else:
            camera = replace(camera, fov=self.vertical_fov(sensor, width, height))
        return camera, RenderSettings(width=width, height=height, spp=spp, sampler=sampler, pixel_filter=pixel_filter,
                                      filter_radius=radius, filter_stddev=stddev, crop=crop)

    @staticmethod
    def crop_window(film: Plugin, width: int, height: int) -> tuple[int, int, int, int] | None:
        """The film's crop window (x, y, width, height) from the image's top-left corner, as Mitsuba's
        film reads it (the crop's size defaults to the image's, its offset to 0); None where it is
        the whole image."""
        names = ("crop_offset_x", "crop_offset_y", "crop_width", "crop_height")
        if not any(film.has(name) for name in names):
            return None
        x, y = film.integer("crop_offset_x", 0), film.integer("crop_offset_y", 0)
        w, h = film.integer("crop_width", width), film.integer("crop_height", height)
        if x < 0 or y < 0 or w < 1 or h < 1 or x + w > width or y + h > height:
            raise film.error(f"the crop window at ({x}, {y}) of size {w}x{h} is not a window of the {width}x{height} "
                             "image (offsets at least 0, a size of at least 1x1, offset + size within the image)")
        return None if (x, y, w, h) == (0, 0, width, height) else (x, y, w, h)

    @staticmethod
    def ortho_height(sensor: Plugin, width: int, height: int) -> float:
        """The height of an orthographic view: Mitsuba's spans [-1, 1] of its camera space across the
        image's width and [-1, 1] / aspect up it, scaled by to_world."""
        matrix = sensor.transform()
        scale_x, scale_y = np.linalg.norm(matrix[:3, 0]), np.linalg.norm(matrix[:3, 1])
        if not math.isclose(scale_x, scale_y, rel_tol=1e-5):
            warn(sensor, "its to_world scales x and y differently (non-square pixels), which Lantern's camera "
                         "does not: the view's height is kept, its width follows the image's")
        return float(2.0 * scale_y * height / width)

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
        """The environment; the scene's lights without a surface join self.lights (emitters.py)."""
        return EmitterReader(self).environment(self.root.objects("emitter"))

    # --- shapes ---------------------------------------------------------------------------------

    def shape_material(self, shape: Plugin) -> str:
        bsdfs = shape.objects("bsdf")
        bsdf = bsdfs[0] if bsdfs else None
        emitters = shape.objects("emitter")
        emission, emission_texture = (0.0, 0.0, 0.0), None
        if emitters:
            emitter = self.visit(emitters[0])
            if emitter.type != "area":
                leave_out(emitter, "only area emitters can sit on a shape: left out")
            else:
                emission, emission_texture = EmitterReader(self).area(emitter)
        base = self.material(bsdf) if bsdf is not None else self.default_material()
        medium = self.interior(shape)
        if max(emission) <= 0.0 and not medium:
            return base.name
        suffix = "+".join(part for part in ("emitter" if max(emission) > 0.0 else "", medium) if part)
        name = f"{base.name}+{suffix}"
        taken = {m.name for m in self.materials}
        if name in taken:
            name = next(f"{name}#{k}" for k in range(2, len(taken) + 2) if f"{name}#{k}" not in taken)
        self.materials.append(replace(base, name=name, emission=emission, emission_texture=emission_texture,
                                      medium=medium))
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
        name = medium.id or f"medium{len(self.media)}"
        spec = medium_spec(self, medium, name)  # (media.py; None: left out with a warning)
        if spec is None:
            return ""
        self.media.append(spec)
        return name

    def default_material(self) -> MaterialSpec:
        for m in self.materials:
            if m.name == "default":
                return m
        spec = MaterialSpec(name="default", kind="diffuse", base_color=DEFAULT_REFLECTANCE, sidedness="back_black")
        self.materials.append(spec)
        return spec

    # --- BSDFs ----------------------------------------------------------------------------------

    def material(self, bsdf: Plugin) -> MaterialSpec:
        key = id(bsdf)
        if key in self.material_of:
            return next(m for m in self.materials if m.name == self.material_of[key])
        spec = with_mesh_attribute(self, self.bsdf(self.visit(bsdf)), bsdf)
        spec = replace(spec, name=bsdf.id or f"{bsdf.type}{len(self.materials)}")
        if any(m.name == spec.name for m in self.materials):
            spec = replace(spec, name=f"{spec.name}#{len(self.materials)}")
        self.materials.append(spec)
        self.material_of[key] = spec.name
        return spec

    def bsdf(self, bsdf: Plugin) -> MaterialSpec:
        return bsdf_spec(self, bsdf)

    # --- values -----------------------------------------------------------------------------------

    def base_colour(self, plugin: Plugin, name: str, default) -> tuple[tuple, TextureSpec | None]:
        """A colour parameter that may hold a bitmap or checkerboard texture: (the colour the
        texture multiplies, the texture or None)."""
        value = plugin.properties.get(name)
        if isinstance(value, Plugin) and value.kind == "texture" and value.type in ("bitmap", "checkerboard"):
            plugin.used.add(name)
            return (1.0, 1.0, 1.0), self.texture(self.visit(value))
        if is_mesh_attribute(value):  # per vertex or face: material() gives the spec its attribute
            plugin.used.add(name)
            return (1.0, 1.0, 1.0), None
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


def _rgb_text(rgb) -> str:
    return "(" + ", ".join(f"{c:g}" for c in rgb) + ")"

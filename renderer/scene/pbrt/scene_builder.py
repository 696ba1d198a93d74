"""A parsed pbrt-v4 scene (directives.py) made into Lantern's plain scene description: the camera
and render settings from the options block, materials (materials.py), shapes (shapes.py), lights
and the environment (lights.py). What has no counterpart is left out with one PbrtSceneWarning
naming file, line and directive; so is every parameter nothing read.

pbrt's camera space is left-handed: its x axis is the image's right, y up, z forward, so a bare
LookAt shows the world mirrored to a right-handed camera's eye (exported scenes put `Scale -1 1 1`
first to undo it). Lantern's camera is right-handed (right = forward x up); where pbrt's image
is mirrored against it, the whole scene is reflected through the plane of the camera's forward
and up, which shows Lantern's camera pbrt's image.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from renderer.scene.description import CameraSpec, FogSpec, RenderSettings, Scene
from renderer.scene.errors import SceneError
from renderer.scene.schema_types import EXPOSURE_EV
from renderer.scene.pbrt.directives import Directive, ParsedScene
from renderer.scene.pbrt.lights import area_emission, image_environment, read_lights
from renderer.scene.pbrt.materials import MaterialReader
from renderer.scene.pbrt.scene_warnings import warn, warn_unused
from renderer.scene.pbrt.shapes import light_areas, shape_objects

DEFAULT_RESOLUTION = (1280, 720)  # pbrt-v4's film
DEFAULT_SPP = 16
DEFAULT_MAX_DEPTH = 5
PATH_INTEGRATORS = ("volpath", "path", "bdpt", "mlt", "sppm", "lightpath", "simplepath", "simplevolpath",
                    "randomwalk")
QUIET = {"Film": ("filename", "savefp16", "diagonal"), "Sampler": ("seed", "randomization", "jitter"),
         "Integrator": ("regularize", "lightsampler", "samplelights", "samplebsdf", "rrthreshold"),
         "Camera": ("shutteropen", "shutterclose")}


def build_scene(parsed: ParsedScene, model_files) -> Scene:
    return _Builder(parsed, model_files).scene()


class _Builder:
    def __init__(self, parsed: ParsedScene, model_files):
        self.parsed, self.model_files = parsed, model_files
        self.materials, self.media, self.source_files = [], [], list(parsed.files)
        self.reader = MaterialReader(parsed, self)
        self.emission: dict[int, tuple] = {}
        self.shapes: dict[int, list] = {}  # id(Shape directive) -> its mesh objects and frames

    def scene(self) -> Scene:
        path = self.parsed.path
        camera, render, mirror = self.camera_and_settings()
        lights, environment = read_lights(self.parsed.lights)
        objects = []
        for d in self.parsed.shapes:
            objects += self.place(d, np.eye(4))
        for name, ctm, token in self.parsed.instances:
            for d in self.parsed.objects[name]:
                objects += self.place(d, ctm, instanced=True)
        if not objects:
            raise SceneError(path, "nothing Lantern can render: the scene has no shape it supports")
        if mirror is not None:
            objects = [replace(o, to_world=_rows(mirror @ o.matrix())) for o in objects]
            lights = [_mirrored_light(mirror, light) for light in lights]
        if isinstance(environment, Directive):
            environment = image_environment(environment, mirror, self.model_files.options.budget)
        fog = FogSpec()
        medium = self.reader.medium(self.parsed.camera_medium, self.parsed.options.get("Camera")) \
            if self.parsed.camera_medium else ""
        if medium:
            fog = FogSpec(model="medium", medium=medium)
        return Scene(name=path.name.split(".")[0], path=path, geometry="mesh", camera=camera, render=render,
                     environment=environment, materials=tuple(self.materials), mesh_objects=tuple(objects),
                     media=tuple(self.media), fog=fog, lights=tuple(lights),
                     source_files=tuple(dict.fromkeys(self.source_files)),
                     description=f"pbrt-v4 scene {path.name}", model_files=self.model_files)

    # --- shapes -----------------------------------------------------------------------------------

    def place(self, d: Directive, outer: np.ndarray, instanced: bool = False) -> list:
        base = self.reader.of_shape(d.material)
        emission, power, two_sided = (0.0, 0.0, 0.0), -1.0, False
        if d.area_light is not None and id(d.area_light) not in self.emission:
            if instanced:
                warn(d.area_light, "area lights on object instances are not supported (nor in pbrt-v4): "
                                   "the instances do not emit")
                self.emission[id(d.area_light)] = (0.0, 0.0, 0.0), -1.0, False
            else:
                self.emission[id(d.area_light)] = area_emission(d.area_light)
        if d.area_light is not None and not instanced:
            emission, power, two_sided = self.emission[id(d.area_light)]
        inside, outside = self.media_of(d)
        if id(d) not in self.shapes:  # an object's shapes are read once, however many instances place them
            self.shapes[id(d)] = shape_objects(d, base.name, self.model_files)
        placed = []
        for obj, frame in self.shapes[id(d)]:
            matrix = outer @ d.ctm @ frame
            if not np.all(np.isfinite(matrix)) or abs(np.linalg.det(matrix[:3, :3])) < 1e-30:
                raise d.error("its transform is singular")
            placed.append((obj, matrix))
        if power > 0 and max(emission) > 0:
            areas = [a for obj, matrix in placed for a in light_areas(d, obj, matrix, self.model_files)]
            if areas and max(areas) > 1.01 * min(areas):
                warn(d, "its area light's power gives each part (triangle or patch) of it its own radiance in "
                        "pbrt; their parts differ in area, so the radiance of their mean area is used")
            if areas and min(areas) > 0:
                emission = tuple(c * power / (math.pi * float(np.mean(areas))) for c in emission)
        material = self.reader.with_surface(base, emission, inside, outside, self.reader.alpha(d), two_sided)
        return [replace(obj, material=material, to_world=_rows(matrix)) for obj, matrix in placed]

    def media_of(self, d: Directive) -> tuple[str, str]:
        """(Lantern's medium inside the shape, its outside medium: "" for the scene's, which is the
        camera's). pbrt's shape without a medium transition (inside = outside) leaves a ray in the
        medium it was in: the one named on both sides, else the camera's."""
        camera = self.parsed.camera_medium
        if d.inside == d.outside:
            if not d.inside:
                return self.reader.medium(camera, d), ""
            named = self.reader.medium(d.inside, d)
            return named, "" if d.inside == camera else named
        inside = self.reader.medium(d.inside, d)
        if d.outside == camera:
            return inside, ""
        if not d.outside:
            warn(d, f"empty space outside the shape while the camera is in the medium '{camera}' is not supported: "
                    "the camera's medium stands there")
            return inside, ""
        return inside, self.reader.medium(d.outside, d)

    # --- camera and options -----------------------------------------------------------------------

    def option(self, name: str) -> Directive | None:
        return self.parsed.options.get(name)

    def camera_and_settings(self) -> tuple[CameraSpec, RenderSettings, np.ndarray | None]:
        render = self.film()
        render = self.sampler(render)
        render = self.integrator(render)
        render = self.pixel_filter(render)
        cam = self.option("Camera")
        ctm = cam.ctm if cam is not None else np.eye(4)
        world_from_camera = np.linalg.inv(ctm)
        m3 = world_from_camera[:3, :3]
        position = world_from_camera[:3, 3]
        forward = m3 @ np.array([0.0, 0.0, 1.0])
        forward /= np.linalg.norm(forward)
        up = m3 @ np.array([0.0, 1.0, 0.0])
        up = up - forward * np.dot(up, forward)
        up /= np.linalg.norm(up)
        right = np.cross(forward, up)  # Lantern's image right
        mirror = None
        if np.dot(m3 @ np.array([1.0, 0.0, 0.0]), right) < 0.0:
            mirror = np.eye(4)
            mirror[:3, :3] -= 2.0 * np.outer(right, right)
            mirror[:3, 3] = 2.0 * np.dot(right, position) * right
        camera = CameraSpec(position=_vec(position), look_at=_vec(position + forward), up=_vec(up))
        if cam is None:
            return replace(camera, fov=self.vertical_fov(90.0, render)), render, mirror
        p = cam.params
        kind = cam.type
        if kind not in ("perspective", "orthographic"):
            warn(cam, "rendered as a perspective camera (only perspective and orthographic are supported)")
            for q in p.params:
                q.used = True
            kind = "perspective"
        if p.has("screenwindow") or p.has("frameaspectratio"):
            warn(cam, "screenwindow and frameaspectratio are not supported: the image's own aspect is used")
            p.find("screenwindow"), p.find("frameaspectratio")
        lens = p.float("lensradius", 0.0)
        focus = p.float("focaldistance", 1e6)
        camera = replace(camera, aperture=lens, focus_distance=focus)
        if kind == "orthographic":
            w, h = render.width, render.height
            camera = replace(camera, projection="orthographic", ortho_height=2.0 if w >= h else 2.0 * h / w)
        else:
            fov = p.float("fov", 90.0)
            if not 0.0 < fov < 180.0:
                raise cam.error(f"fov {fov:g} is not between 0 and 180 degrees")
            camera = replace(camera, fov=self.vertical_fov(fov, render))
        self.unused(cam)
        return camera, render, mirror

    @staticmethod
    def vertical_fov(fov: float, render: RenderSettings) -> float:
        """pbrt's fov spans the image's shorter side; Lantern's is vertical."""
        if render.width >= render.height:
            return fov
        half = math.tan(math.radians(fov) / 2.0) * render.height / render.width
        return math.degrees(2.0 * math.atan(half))

    def film(self) -> RenderSettings:
        film = self.option("Film")
        width, height = DEFAULT_RESOLUTION
        if film is None:
            return RenderSettings(width=width, height=height, exposure=self.exposure(None))
        if film.type not in ("rgb", "gbuffer", "spectral"):
            warn(film, "read as an rgb film")
        elif film.type != "rgb":
            warn(film, "written as an rgb film (its extra channels are left out)")
        p = film.params
        width, height = p.integer("xresolution", width), p.integer("yresolution", height)
        if width < 1 or height < 1:
            raise film.error(f"a {width}x{height} image has no pixels")
        crop = None
        window = p.floats("cropwindow")
        if window is not None:
            if len(window) != 4 or not (0 <= window[0] < window[1] <= 1 and 0 <= window[2] < window[3] <= 1):
                raise film.error("cropwindow takes [x0 x1 y0 y1], fractions of the image with x0 < x1 and y0 < y1")
            x0, x1 = math.ceil(width * window[0]), math.ceil(width * window[1])
            y0, y1 = math.ceil(height * window[2]), math.ceil(height * window[3])
            if x1 > x0 and y1 > y0 and (x0, y0, x1, y1) != (0, 0, width, height):
                crop = (x0, y0, x1 - x0, y1 - y0)
        exposure = self.exposure(film)
        self.unused(film)
        return RenderSettings(width=width, height=height, crop=crop, exposure=exposure)

    def exposure(self, film: Directive | None) -> float:
        """pbrt-v4's imaging ratio, shutter time x iso / 100, which scales the values its film
        records, as Lantern's display exposure in EV (Lantern's EXR keeps radiance). White balance
        and camera sensors other than cie1931 (which white-balance to 6500 K) are one warning."""
        cam = self.option("Camera")
        shutter = (cam.params.float("shutterclose", 1.0) - cam.params.float("shutteropen", 0.0)) if cam else 1.0
        iso = film.params.float("iso", 100.0) if film is not None else 100.0
        ratio = shutter * iso / 100.0
        if not ratio > 0.0:
            raise (film or cam).error(f"shutter time x iso / 100 is {ratio:g}: the film records no light")
        exposure = math.log2(ratio)
        if exposure not in EXPOSURE_EV:
            raise (film or cam).error(f"shutter time x iso / 100 = {ratio:g} is beyond 2^-126 .. 2^127")
        if film is None:
            return exposure
        sensor, balance = film.params.string("sensor", "cie1931"), film.params.float("whitebalance", 0.0)
        if sensor != "cie1931" or balance != 0.0:
            warn(film, f"the sensor '{sensor}' and white balance are not supported: the image is the cie1931 "
                       "sensor's, not white-balanced")
        return exposure

    def sampler(self, render: RenderSettings) -> RenderSettings:
        sampler = self.option("Sampler")
        if sampler is None:
            return replace(render, spp=DEFAULT_SPP, sampler="sobol")
        p = sampler.params
        if sampler.type == "stratified":
            spp = p.integer("xsamples", 4) * p.integer("ysamples", 4)
        else:
            spp = p.integer("pixelsamples", DEFAULT_SPP)
        if spp < 1:
            raise sampler.error(f"{spp} samples per pixel: at least one")
        seed = p.integer("seed", 0)
        self.unused(sampler)
        return replace(render, spp=spp, seed=max(seed, 0),
                       sampler="independent" if sampler.type == "independent" else "sobol")

    def integrator(self, render: RenderSettings) -> RenderSettings:
        # pbrt's rough BSDFs scatter once: its scenes render without Lantern's energy compensation
        render = replace(render, energy_compensation=False, integrator="mis", max_depth=DEFAULT_MAX_DEPTH + 1)
        d = self.option("Integrator")
        if d is None:
            return render
        if d.type not in PATH_INTEGRATORS:
            warn(d, "rendered with Lantern's path tracer (mis)")
            for q in d.params.params:
                q.used = True
            return render
        depth = d.params.integer("maxdepth", DEFAULT_MAX_DEPTH)
        if depth < 0:
            raise d.error(f"maxdepth {depth} is negative")
        if d.type == "sppm":
            render = self.photon_mapping(d, render)
        elif d.type not in ("volpath", "path"):  # bdpt, mlt, ...: other estimators of the same image
            warn(d, "rendered with Lantern's path tracer (mis), which estimates the same image")
            for q in d.params.params:
                q.used = True  # (their own knobs: mutations, light paths)
        # pbrt counts bounces (1: direct light only); Lantern counts as Mitsuba (2: direct light),
        # and a maxdepth of 0 shows only what the camera sees emit
        return replace(render, max_depth=depth + 1)

    def photon_mapping(self, d: Directive, render: RenderSettings) -> RenderSettings:
        """pbrt's sppm as Lantern's: the caustics of small lights behind glass (water-caustic) are
        what a path tracer cannot find. Lantern's search radius starts at two pixel footprints."""
        if self.parsed.media or self.parsed.camera_medium:
            why = "Lantern's sppm does not simulate media"
        elif any(light.type in ("point", "spot", "distant", "goniometric", "projection") for light in self.parsed.lights):
            why = "Lantern's sppm emits photons from area lights and environments only"
        else:
            why = ""
        if why:
            warn(d, f"{why}: rendered with its path tracer (mis)")
            return render
        if d.params.has("radius"):
            d.params.find("radius")
            warn(d, "sppm's radius: Lantern's initial search radius is two pixel footprints at each visible point")
        if d.params.integer("photonsperiteration", -1) > 0:
            warn(d, "sppm's photonsperiteration: Lantern emits one photon per pixel in each iteration")
        return replace(render, integrator="sppm")

    def pixel_filter(self, render: RenderSettings) -> RenderSettings:
        d = self.option("PixelFilter")
        if d is None:
            return replace(render, pixel_filter="gaussian", filter_stddev=0.5)
        p = d.params
        defaults = {"box": 0.5, "gaussian": 1.5, "triangle": 2.0, "mitchell": 2.0, "sinc": 4.0}
        rx = p.float("xradius", defaults.get(d.type, 0.5))
        ry = p.float("yradius", defaults.get(d.type, 0.5))
        if rx != ry:
            warn(d, f"xradius and yradius differ: {rx:g} is used for both")
        if d.type == "box":
            if rx != 0.5:
                warn(d, "Lantern's box filter is one pixel wide: radius 0.5 is used")
            render = replace(render, pixel_filter="box")
        elif d.type == "gaussian":
            render = replace(render, pixel_filter="gaussian", filter_stddev=p.float("sigma", 0.5))
        elif d.type == "triangle":
            render = replace(render, pixel_filter="tent", filter_radius=rx)
        else:
            warn(d, f"the {d.type} filter is rendered with the box filter")
            for q in p.params:
                q.used = True
            render = replace(render, pixel_filter="box")
        self.unused(d)
        return render

    def unused(self, d: Directive) -> None:
        for name in QUIET.get(d.name, ()):
            d.params.find(name)
        warn_unused(d)


def _vec(v) -> tuple:
    return tuple(float(x) for x in v)


def _rows(m: np.ndarray) -> tuple:
    return tuple(tuple(float(x) for x in row) for row in m)


def _mirrored_light(mirror: np.ndarray, light):
    m3 = mirror[:3, :3]
    return replace(light, position=_vec(mirror @ np.array([*light.position, 1.0]))[:3],
                   direction=_vec(m3 @ np.array(light.direction)), up=_vec(m3 @ np.array(light.up)))

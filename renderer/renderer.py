"""The Renderer: uploads a scene once, then renders progressive passes into its film.

It is what the viewer, the command line and the benchmarks drive; it knows nothing of windows.
"""
from __future__ import annotations

import warnings

from dataclasses import dataclass, replace

import numpy as np
import taichi as ti

from renderer.film.adaptive import DEFAULT_MIN_SPP, AdaptiveSampling, is_check_point, next_check
from renderer.film.aovs import AovFilm, scene_feature_boost
from renderer.runtime.allocation import allocation_size
from renderer.film.band_table import BandTable
from renderer.film.crop_window import FilmWindow, film_window
from renderer.camera import CameraFrame
from renderer.film.accumulation import Film, FilmState
from renderer.output.image_io import read_environment
from renderer.integrators import make_integrator
from renderer.lights.environment import Environment
from renderer.materials.table import MaterialRows, MaterialTable
from renderer.materials.texture_sampler import TextureTable
from renderer.media.table import MediaTable
from renderer.film.pixel_fields import pixel_vector, row_sums
from renderer.film.pixel_slices import (BANDS, INTERLEAVED, ROUND_SLICES, band_rows_array, bit_reverse_array,
                                   filled_mean_array)
from renderer.program import RenderProgram
from renderer.sampling.sampler import make_sampler
from renderer.scene.features import Features, scene_features
from renderer.scene.description import Scene


@dataclass(frozen=True)
class MeshOptions:
    """Compile-time and build-time choices of the mesh world (benchmarked knobs)."""

    strategy: str = "sah"
    # "wide8" (the binary tree collapsed into 8-wide nodes), "wide4", or the binary tree's "stack" or
    # "stackless" (renderer/geometry/mesh_geometry.py; `bench bvh` compares them). 8-wide since its
    # visits lost their sorting network (docs/findings.md, "Nearest child first"): whole `mis`
    # renders 1.02-1.12x faster than 4-wide, the 1M terrain's incoherent rays 1.17x.
    traversal: str = "wide8"
    triangle_test: str = "watertight"
    # "packets" (leaves tested four slots at a time, triangles structure-of-arrays), "scalar"
    # (renderer/geometry/triangle_packets.py; `bench bvh` compares them), or "auto": packets where
    # triangles are at least half the primitives (analytic quads, spheres and discs are tested
    # lane by lane in a packet, which cost the Cornell box's quads 5 %)
    leaves: str = "auto"
    # None: the leaf layout's own (MAX_LEAF_SIZE): packet leaves pay for larger leaves (four
    # triangles cost about one), scalar ones do not
    max_leaf_size: int | None = None
    instancing: bool = True  # False: every instance flattened into world triangles (a reference)
    # Rays a packet on the CPU (renderer/packets/: 4, 8 or 16 lanes, one path a lane), for the
    # combinations renderer/packets/support.py admits; 0: one ray per loop index throughout.
    packets: int = 0


# Measured (docs/findings.md, "Leaves tested four at a time"): with packet leaves, bench bvh's
# leaf sweep on the 100k terrain gave 3.99/3.88/4.36/4.92/4.85 Mrays/s incoherent at max leaf
# 1/2/4/8/16, and whole `mis` renders ran 1.02-1.05x (stress) and 1.01x (bunnies) at 8 against 4;
# scalar leaves of triangles keep 4 (textured with scalar leaves: 1 and 2 ran 0.95x of 4).
MAX_LEAF_SIZE = {"scalar": 4, "packets": 8}
# Scenes of mostly analytic primitives (quads, spheres, discs, Bezier patches; scalar leaves): no
# forced leaf size, SAH decides where to stop (its leaves hold at most 16). Under 8-wide nodes, whose
# eight boxes are tested together, a leaf of four quads cost the Cornell box four scalar tests where
# the node would have culled most: whole `mis` renders at max leaf 1 against 4, in one process
# (docs/findings.md, "Analytic scenes"): Cornell box 1.25x, goblet 1.09x, weekend 0.99x.
ANALYTIC_MAX_LEAF_SIZE = 1


def max_leaf_size(options: MeshOptions, layout: str, counts: dict | None = None) -> int:
    """The BVH's max leaf size for a leaf layout ("scalar" or "packets") and the world's primitive
    counts: the options' own; else ANALYTIC_MAX_LEAF_SIZE for scalar leaves over mostly analytic
    primitives; else the layout's (MAX_LEAF_SIZE)."""
    if options.max_leaf_size is not None:
        return options.max_leaf_size
    if layout == "scalar" and counts is not None:
        total = sum(counts.values())
        if total and 2 * counts.get("triangle", 0) < total:
            return ANALYTIC_MAX_LEAF_SIZE
    return MAX_LEAF_SIZE[layout]


def leaf_layout(leaves: str, data) -> str:
    """MeshOptions.leaves for mesh data: "auto" resolved by the share of triangles."""
    if leaves != "auto":
        return leaves
    counts = data.counts
    total = sum(counts.values())
    return "packets" if total and 2 * counts.get("triangle", 0) >= total else "scalar"


def build_world(scene: Scene, mesh_options: MeshOptions):
    """(geometry, material table, Features with the scene camera's lens, the mesh scene's assembly
    or None) for any scene kind."""
    if scene.geometry == "sdf":
        from shaders_sdf.geometry import SdfGeometry

        return (SdfGeometry(scene, scene.material_index), MaterialTable.from_specs(scene.materials, scene.medium_names()),
                scene_features(scene), None)
    if scene.geometry == "mesh":
        from renderer.geometry.instance_bvh import build_scene_bvh
        from renderer.geometry.mesh_geometry import MeshGeometry
        from renderer.mesh_world import prepare_mesh_scene as assemble

        mesh = assemble(scene, instancing=mesh_options.instancing)
        layout = leaf_layout(mesh_options.leaves, mesh.data)
        bvh = build_scene_bvh(mesh.data, strategy=mesh_options.strategy,
                              max_leaf_size=max_leaf_size(mesh_options, layout, mesh.data.counts))
        textures = TextureTable(mesh.atlas, mesh.texture_slots, scene.render.texture_filter)
        materials = MaterialTable(mesh.rows, textures, mesh.volume_media)
        # The geometry tests alpha coverage during traversal: it reads the material table.
        geometry = MeshGeometry(mesh.data, bvh, mesh_options.traversal, mesh_options.triangle_test, materials,
                                layout)
        return geometry, materials, mesh.features(scene), mesh
    raise ValueError(f"unknown geometry kind '{scene.geometry}'")


@dataclass(frozen=True)
class SurfaceHit:
    """The first surface along a camera ray (Renderer.pick): distance along the unit ray, the point,
    its shading normal and texture coordinates, the distance along the view direction (depth: what
    the lens focuses on), its material row (a place in the scene's material list, then model
    files' materials), the primitive (a global id on meshes, a node of the SDF tree), the mesh
    instance (-1: none) and whether the ray met the front face."""

    distance: float
    point: tuple
    normal: tuple
    uv: tuple
    depth: float
    material: int
    primitive: int
    instance: int
    front_face: bool


@dataclass(frozen=True)
class AdaptiveSettings:
    """Adaptive sampling (renderer/film/adaptive.py): stop pixels whose relative standard error is
    below `threshold`, once they have `min_spp` samples."""

    threshold: float
    min_spp: int = DEFAULT_MIN_SPP


# Samples per pixel one launch may take on Vulkan. On lavapipe (the only Vulkan driver tried)
# pixels stopped short of the samples a launch asked of them: hard_cases / mis at 80x45, one
# launch of 256: 4-89 each; the Cornell box / normals, 4 or more a launch: the last, partial
# group of 128 pixels took 3. One or two a launch were exact in every case tried; the cause (the
# driver or Taichi's SPIR-V) is not found. The CPU takes every sample; scripts/gpu_check.py
# checks each pixel's count on CUDA (its one run so far agreed in images but did not read them).
VULKAN_SAMPLES_PER_LAUNCH = 1


def samples_per_launch_limit() -> int:
    """The most samples per pixel one render launch takes on the running Taichi back-end."""
    return VULKAN_SAMPLES_PER_LAUNCH if ti.lang.impl.current_cfg().arch == ti.vulkan else 1 << 30


class Renderer:
    def __init__(self, scene: Scene, max_size: tuple[int, int] | None = None,
                 mesh_options: MeshOptions = MeshOptions(), aovs: bool = False):
        """`aovs`: also accumulate the denoising AOVs (renderer/film/aovs.py) of integrators that write
        them; 28 bytes a pixel more."""
        self.scene = scene
        width, height = max_size or scene.render.image_size
        image = (read_environment(scene.environment.file, scene.model_files.options.budget)
                 if scene.environment.kind == "map" else None)
        self.environment = Environment(scene.environment, image)
        self.geometry, self.materials, self._features, self._mesh = build_world(scene, mesh_options)
        if mesh_options.packets:  # (the packet modules imported only where packets are asked for)
            from renderer.packets.support import PACKET_WIDTHS

            if mesh_options.packets not in PACKET_WIDTHS:
                raise ValueError(f"packets of {mesh_options.packets} rays (choose from 0 (off), "
                                 f"{', '.join(map(str, PACKET_WIDTHS))})")
        self.packet_width = mesh_options.packets
        self._packet_lights = None  # PacketLights, built with the first packet program
        self._packet_records = None  # PrimitiveRecords, likewise (kept: the geometry does not change)
        self._packet_reasons: dict[tuple, str | None] = {}  # packet_reason's, until emission changes
        self.media = MediaTable(scene, self.materials.volume_media)
        self._env_image = image
        self._lights = None
        self._scene_radius: float | None = None
        allocated = allocation_size(width, height)  # shared compiled programs across nearby sizes
        self.film = Film(*allocated)
        self.aovs = AovFilm(*allocated) if aovs else None
        # Feature samples (renderer/film/aovs.py) each of a pixel's first colour samples brings where
        # AOVs are kept, as the scene calls for; the viewer sets 0 while nothing will be denoised.
        self.scene_feature_boost = scene_feature_boost(self._features) if aovs else 0
        self.feature_boost = self.scene_feature_boost
        self.adaptive: AdaptiveSettings | None = None  # set_adaptive()
        self._adaptive_rule = None
        self.pixels_active = width * height  # pixels adaptive sampling has not stopped
        self.work = pixel_vector(3, ti.f32, allocated)
        self.bands = BandTable(allocated[1])
        self._pick_out = (ti.field(ti.f32, shape=10), ti.field(ti.i32, shape=5))  # pick()'s (floats, ints)
        self._programs: dict[tuple, RenderProgram] = {}  # by _program_key
        # Per-integrator knobs that are data, not compile-time (e.g. "sppm": SppmOptions), and
        # device state that integrators with their own programs share between them (shared()).
        self.integrator_options: dict[str, object] = {}
        self._shared: dict[str, object] = {}
        self._launched: set[tuple] = set()  # program keys launched in this process
        self.slices_done = 0  # pixel slices rendered since the last reset (renderer/film/pixel_slices.py)
        # Rounds after the first cut into bands of rows (pixel_slices.BANDS) rather than interleaved:
        # the viewer's still frames, whose passes are a few slices each. Renders that save or share
        # partial rounds (checkpoints, distributed groups) keep the interleaved order throughout.
        self.bands_after_first_round = False
        self.samples_per_launch = samples_per_launch_limit()
        self._window: FilmWindow | None = None  # film_window(), for the film size _window_for
        self._window_for: tuple[int, int] | None = None
        self.reset(width, height)

    # --- programs ------------------------------------------------------------------------------
    def features(self, camera: CameraFrame | None = None) -> Features:
        """The scene's Features, with the lens model and projection of `camera` (the viewer's aperture
        slider)."""
        if camera is None:
            return self._features
        return replace(self._features, depth_of_field=camera.aperture > 0.0, orthographic=camera.orthographic)

    def program(self, integrator: str, features: Features, sampler: str = "independent") -> RenderProgram:
        key = self._program_key(integrator, features, sampler)
        if key not in self._programs:
            chosen = make_integrator(integrator)
            lights = self.lights() if getattr(chosen, "uses_lights", False) else None
            if key[4]:
                self._programs[key] = self._packet_program(chosen, features, key)
            elif hasattr(chosen, "make_program"):  # a multi-pass integrator (sppm) brings its own kernels
                if features.pixel_filter[0] != "box":
                    warnings.warn(f"{self.scene.name}: {integrator} gathers photons per pixel and renders with the "
                                  f"box filter, not the scene's {features.pixel_filter[0]} filter", stacklevel=3)
                self._programs[key] = chosen.make_program(self, features, make_sampler(sampler), lights)
            else:
                self._programs[key] = RenderProgram(self.geometry, self.materials, self.environment, chosen,
                                                    self.film, self.work, features, make_sampler(sampler), lights,
                                                    self.media, self.aovs, self.bands, key[3])
        return self._programs[key]

    def _program_key(self, integrator: str, features: Features, sampler: str) -> tuple:
        """A program's cache key: the combination, and whether its kernel has the AOVs' feature
        samples compiled in: where the scene calls for them (its textures), so the viewer's toggle
        of the denoised view compiles nothing, or where feature_boost asks for them elsewhere."""
        return (integrator, features, sampler, self._feature_samples(),
                self.packet_width if self.packet_width and self.packet_reason(integrator, features, sampler) is None
                else 0)

    def _feature_samples(self) -> bool:
        """Whether kernels take the AOVs' feature samples (renderer/film/aovs.py)."""
        return self.aovs is not None and (self.feature_boost > 0 or self.scene_feature_boost > 0)

    def packet_reason(self, integrator: str, features: Features, sampler: str) -> str | None:
        """Why this combination renders one ray at a time though packets were asked for (None:
        it takes packets)."""
        feature_samples = self._feature_samples()
        key = (integrator, features, sampler, feature_samples)
        if key not in self._packet_reasons:
            from renderer.materials.kinds import NO_TEXTURE
            from renderer.packets.support import unsupported

            textured_emission = (self.scene.geometry == "mesh"
                                 and bool((self.materials.arrays["textures"][:, 3] != NO_TEXTURE).any()))
            self._packet_reasons[key] = unsupported(self.geometry, features, integrator, sampler,
                                                    feature_samples, textured_emission)
        return self._packet_reasons[key]

    def packet_status(self, integrator: str, features: Features, sampler: str) -> str | None:
        """What became of the packets asked for, in a line ("packets of 8 rays: taken", or not
        taken and why); None where none were asked for."""
        if not self.packet_width:
            return None
        reason = self.packet_reason(integrator, features, sampler)
        if reason is not None:
            return f"packets of {self.packet_width} rays: not taken, {reason}"
        from renderer.packets.support import scalar_bounces

        taken = "taken"
        if scalar_bounces(self.geometry):
            taken += f" (bounce and shadow rays one at a time among {self.geometry.primitive_count():,} primitives)"
        return f"packets of {self.packet_width} rays: {taken}"

    def _packet_program(self, chosen, features: Features, key: tuple):
        from renderer.packets.lights import PacketLights
        from renderer.packets.program import PacketProgram
        from renderer.packets.records import PrimitiveRecords

        if self._packet_records is None:
            self._packet_records = PrimitiveRecords(self.geometry.data)
        if self._packet_lights is None:
            self._packet_lights = PacketLights(self.geometry, self._packet_records, self.materials, self.environment,
                                               self.scene.environment, self._env_image)

        def scalar():
            return RenderProgram(self.geometry, self.materials, self.environment, chosen, self.film, self.work,
                                 features, make_sampler(key[2]), self.lights() if chosen.uses_lights else None,
                                 self.media, self.aovs, self.bands, key[3])

        return PacketProgram(self.geometry, self._packet_records, self.materials, self.environment, chosen, self.film,
                             self.work, features, self._packet_lights, self.bands, key[4], scalar, self.aovs)

    def lights(self):
        """The scene's emitters for direct lighting, built on first use (light selection structures
        cost nothing to integrators that do not sample lights)."""
        if self._lights is None:
            from renderer.lights.delta_lights import DeltaLights
            from renderer.lights.lights import Lights, emitter_table

            emitters = emitter_table(self.geometry, self.materials.arrays)
            delta = (DeltaLights(self.scene.lights, self.scene_radius(), ledger=self.scene.model_files.ledger)
                     if self.scene.lights else None)
            self._lights = Lights(self.geometry, emitters, self.environment, self.scene.environment, self._env_image,
                                  delta=delta)
        return self._lights

    def scene_radius(self) -> float:
        """The radius of a sphere about the scene (a directional light's power is what crosses it):
        a mesh scene's bounding sphere; an SDF scene has no finite bounds (planes, repetition), so
        the distance from its camera to the point it looks at stands in. Computed once (edits keep
        the geometry and the camera)."""
        if self._scene_radius is None:
            data = getattr(self.geometry, "data", None)
            if self.scene.geometry == "mesh" and data is not None and data.primitive_count:
                lo, hi = data.scene_bounds()
                self._scene_radius = max(0.5 * float(np.linalg.norm(np.asarray(hi) - np.asarray(lo))), 1e-3)
            else:
                camera = self.scene.camera
                self._scene_radius = max(float(np.linalg.norm(np.subtract(camera.look_at, camera.position))), 1e-3)
        return self._scene_radius

    def shared(self, name: str, build):
        """A device object built once per Renderer by `build()` and shared by the programs that ask
        for it by `name` (e.g. SPPM's per-pixel state, sized to the film)."""
        if name not in self._shared:
            self._shared[name] = build()
        return self._shared[name]

    def is_compiled(self, integrator: str, features: Features, sampler: str = "independent") -> bool:
        """False until the combination has run once in this process (its first call compiles)."""
        return self._program_key(integrator, features, sampler) in self._launched

    # --- editing -------------------------------------------------------------------------------
    def edit_materials(self, scene: Scene) -> bool:
        """Adopt `scene`: this renderer's scene with its materials edited (the same names in the
        same order, the rest unchanged). The material rows are uploaded again in place and the
        film is reset; the Features follow the materials, so a kind or effect the edit brings in
        compiles on the next render and one it drops leaves the kernel, while an edit of values
        compiles nothing. Lights are rebuilt where emission changed (their selection weighs it).
        Model files' own materials follow scene.model_material_edits. Returns False, changing
        nothing, where the edit needs the world built again (a texture added, removed or changed; a
        different number of rows, media or rough-plastic tables; an instanced mesh's material
        starting or stopping to emit): make a new Renderer of `scene` then."""
        old = self.scene
        if [m.name for m in scene.materials] != [m.name for m in old.materials]:
            raise ValueError("an edit keeps the scene's materials and their order")
        if any(a.textures != b.textures for a, b in zip(scene.materials, old.materials)):
            return False
        if self._mesh is not None:
            from renderer.mesh_world import material_rows, with_model_edits
            from renderer.scene.mesh_assembly import emits

            materials = tuple(scene.materials) + with_model_edits(self._mesh.materials[len(old.materials):], scene)
            if self._mesh.data.has_instances and any(emits(a) != emits(b) for a, b in zip(materials, self._mesh.materials)):
                return False  # an emitter's instances were flattened into world triangles at assembly
            rows, _ = material_rows(scene, materials, self._mesh.spec_images)
            mesh = replace(self._mesh, rows=rows, materials=materials)
            features = mesh.features(scene)
        else:
            rows, mesh = MaterialRows.of_specs(scene.materials, scene.medium_names()), None
            features = scene_features(scene)
        arrays, before = rows.arrays(), self.materials.arrays
        fits = getattr(self.geometry, "fits_materials", None)  # mesh traversal compiles material flags in
        if scene.medium_names() != old.medium_names() or (fits is not None and not fits(arrays)):
            return False
        if not self.materials.update(rows, arrays):
            return False
        self.scene, self._mesh, self._features = scene, mesh, features
        if self.aovs is not None:
            self.scene_feature_boost = scene_feature_boost(features)
            self.feature_boost = self.scene_feature_boost
        if any(not np.array_equal(before[k], arrays[k]) for k in ("emission", "two_sided_emission")):
            self._refit_lights()
        self.reset()
        return True

    def model_material(self, index: int):
        """A model file's own material as shown (a ModelMaterial: `pbr`, and `file_pbr` where the
        scene edits it), by its number among the model materials; None where there is none."""
        k = len(self.scene.materials) + index
        if self._mesh is None or index < 0 or k >= len(self._mesh.materials):
            return None
        return self._mesh.materials[k]

    def edit_environment(self, spec) -> bool:
        """Adopt an edited environment of the same kind and image (intensity, orientation about
        the axis it was built for, colours): data uploaded in place, the film reset, nothing
        compiled; lights rebuilt where it starts or stops emitting. False, changing nothing,
        where the edit needs it built again (another kind or file, a turn off the +y axis)."""
        old = self.scene.environment
        if (spec.kind, spec.file) != (old.kind, old.file) or spec.needs_matrix != old.needs_matrix:
            return False
        from renderer.lights.lights import environment_emits

        self.environment.set_spec(spec)
        self.scene = replace(self.scene, environment=spec)
        if environment_emits(spec) != environment_emits(old):
            self._drop_packet_programs()
            self._drop_lights()
        else:
            self._refit_photons()
        self.reset()
        return True

    def edit_lights(self, lights) -> bool:
        """Adopt edited point, spot, directional and projector lights (`lights`: the scene's, in
        the same order and kinds, with other values, places, directions or cones): data uploaded
        in place, the film reset, nothing compiled. False, changing nothing, where the edit needs
        the lights built again (another kind or image, a light turned on or off)."""
        old = self.scene.lights
        if [(a.kind, a.texture) for a in lights] != [(b.kind, b.texture) for b in old]:
            return False
        scene = replace(self.scene, lights=tuple(lights))
        features = self._mesh.features(scene) if self._mesh is not None else scene_features(scene)
        if features != self._features:
            return False
        if self._lights is not None:
            delta = self._lights.delta
            if delta is None or not delta.refit(scene.lights, self.scene_radius()):
                return False
            if self._lights.has_delta:
                self._lights.refit_delta()
        self.scene = scene
        self.reset()
        return True

    def _refit_lights(self) -> None:
        """Emission edited: the light structures weigh emitters by their power. The same emitters
        with other powers are taken in place (nothing compiles); where others emit now, the
        structures are built again on next use."""
        self._drop_packet_programs()
        if self._lights is None:
            return
        from renderer.lights.lights import emitter_table

        if self._lights.refit(emitter_table(self.geometry, self.materials.arrays)):
            self._refit_photons()
        else:
            self._drop_lights()

    def _drop_packet_programs(self) -> None:
        """Packet programs and their light selection made again on next use: an emitter starting
        or stopping to emit changes what they compile in."""
        self._packet_reasons.clear()
        if self._packet_lights is not None:
            self._packet_lights = None
            self._programs = {k: p for k, p in self._programs.items() if not k[4]}

    def _refit_photons(self) -> None:
        emission = self._shared.get("photon_emission")
        if emission is not None and not emission.refit(self.scene.environment):
            self._drop_lights()

    def _drop_lights(self) -> None:
        """Lights built again on next use, with the programs that hold them (compiled again, from
        Taichi's cache) and the photon emission that weighs them."""
        self._shared.pop("photon_emission", None)
        if self._lights is not None:
            self._lights = None
            self._programs.clear()

    # --- rendering -----------------------------------------------------------------------------
    def reset(self, width: int | None = None, height: int | None = None) -> None:
        self.film.reset(width or self.film.width, height or self.film.height)
        if self.aovs is not None:
            self.aovs.reset(self.film.width, self.film.height)
        self.work.fill(0.0)
        self.slices_done = 0
        self.pixels_active = self.film.width * self.film.height

    def film_window(self) -> FilmWindow:
        """Where the film's active region lies on the camera's image: the scene's crop window
        (renderer/film/crop_window.py), or the whole image."""
        size = (self.film.width, self.film.height)
        if self._window_for != size:  # cached: a still view launches every frame
            settings = self.scene.render
            self._window = film_window(settings.crop, (settings.width, settings.height), size)
            self._window_for = size
        return self._window

    def set_adaptive(self, settings: AdaptiveSettings | None) -> None:
        """Turn adaptive sampling on (or off: None) for the samples rendered from now on; pixels
        stopped so far stay stopped until the next reset."""
        if settings is not None and not (settings.threshold > 0.0 and settings.min_spp >= 1):
            raise ValueError(f"adaptive sampling: threshold {settings.threshold} must be > 0 and min spp "
                             f"{settings.min_spp} >= 1")
        self.adaptive = settings
        if settings is not None and self._adaptive_rule is None:
            self._adaptive_rule = AdaptiveSampling(self.film)

    def state(self) -> FilmState:
        """The film's exact state with the AOVs' (what a checkpoint keeps)."""
        state = self.film.state()
        if self.aovs is not None:
            state.albedo, state.normal, state.aov_count = self.aovs.state()
        return state

    def restore(self, state: FilmState, slices_done: int) -> None:
        """Continue from `state` (Renderer.state()) with `slices_done` slices rendered."""
        self.film.restore(state)
        if self.aovs is not None:
            if state.albedo is not None and state.normal is not None:
                self.aovs.restore(state.albedo, state.normal, state.aov_samples())
            else:
                self.aovs.reset(self.film.width, self.film.height)
        self.slices_done = slices_done
        if self._adaptive_rule is None and state.adaptive is not None and state.adaptive.any():
            self._adaptive_rule = AdaptiveSampling(self.film)
        self.pixels_active = (self._adaptive_rule.count_active() if self._adaptive_rule is not None
                              else self.film.width * self.film.height)

    def render(self, camera: CameraFrame, spp: int, integrator: str | None = None, max_depth: int | None = None,
               seed: int | None = None, features: Features | None = None, sampler: str | None = None) -> None:
        """Add `spp` samples per pixel to the film's active region (finishing a round in progress first)."""
        self.render_slices(camera, spp * ROUND_SLICES, integrator, max_depth, seed, features, sampler)

    def render_slices(self, camera: CameraFrame, slices: int, integrator: str | None = None,
                      max_depth: int | None = None, seed: int | None = None, features: Features | None = None,
                      sampler: str | None = None, whole_iterations: bool = True) -> None:
        """Render the next `slices` pixel slices (ROUND_SLICES of them make one sample per pixel;
        renderer/film/pixel_slices.py), continuing the round in progress: at most three launches (the
        rest of that round, whole rounds, the start of the next). An integrator whose passes are
        global (sppm) renders whole iterations: at least one, `slices` rounded down to rounds; or,
        with whole_iterations False (the viewer's still frames), `slices` steps of its iterations
        (ROUND_SLICES a whole one), its film changing when an iteration completes."""
        program, seed, max_depth = self._launch(camera, integrator, max_depth, seed, features, sampler)
        width, height = self.film.width, self.film.height
        if not program.sliced:  # steps of whole-image iterations (SppmProgram.advance)
            if whole_iterations:
                slices = max(1, slices // ROUND_SLICES) * ROUND_SLICES
            self.slices_done += program.advance(width, height, slices, self.slices_done, seed, max_depth,
                                                *camera.kernel_args(), window=self.film_window())
            return
        left = slices
        while left > 0 and self.pixels_active > 0:
            cursor = self.slices_done % ROUND_SLICES
            if cursor == 0 and left >= ROUND_SLICES:
                spp, first, count = min(left // ROUND_SLICES, self.samples_per_launch), 0, ROUND_SLICES
                if self.adaptive is not None:  # whole rounds up to the next check at most
                    spp = min(spp, next_check(self.samples_done, self.adaptive.min_spp) - self.samples_done)
            else:
                spp, first, count = 1, cursor, min(left, ROUND_SLICES - cursor)
            program.render(width, height, spp, first, count, self.round_order(), seed, max_depth,
                           *camera.kernel_args(), feature_boost=self.feature_boost, window=self.film_window())
            self.slices_done += spp * count
            left -= spp * count
            if (self.adaptive is not None and self.slices_done % ROUND_SLICES == 0
                    and is_check_point(self.samples_done, self.adaptive.min_spp)):
                self.pixels_active = self._adaptive_rule.check(self.adaptive.threshold, self.adaptive.min_spp)

    def render_pass(self, camera: CameraFrame, spp: int, slice_first: int, slice_count: int,
                    integrator: str | None = None, max_depth: int | None = None, seed: int | None = None,
                    sampler: str | None = None) -> None:
        """`spp` samples for every pixel of slices [slice_first, slice_first + slice_count) whatever
        the round in progress (slices_done is not advanced): a distributed render's worker renders
        its group of pixels this way. Each pixel continues at its own sample index, so the pixels
        end exactly as in a render that took their samples in any other passes."""
        program, seed, max_depth = self._launch(camera, integrator, max_depth, seed, None, sampler)
        if not program.sliced:
            raise ValueError("an integrator with whole-image passes (sppm) cannot render a group of pixels")
        for taken in range(0, spp, self.samples_per_launch):  # each pixel goes on from its own count
            program.render(self.film.width, self.film.height, min(self.samples_per_launch, spp - taken), slice_first,
                           slice_count, INTERLEAVED, seed, max_depth, *camera.kernel_args(),
                           feature_boost=self.feature_boost, window=self.film_window())

    def round_order(self, slices_done: int | None = None) -> int:
        """How the round holding slice `slices_done` since the last reset (default: the next one)
        is cut into slices (pixel_slices.INTERLEAVED or BANDS): the display redraws by it."""
        done = self.slices_done if slices_done is None else slices_done
        return BANDS if self.bands_after_first_round and done >= ROUND_SLICES else INTERLEAVED

    def _launch(self, camera, integrator, max_depth, seed, features, sampler):
        """(program, seed, max depth) of a launch, the scene's settings where none are given."""
        settings = self.scene.render
        integrator = integrator or settings.integrator
        sampler = sampler or settings.sampler
        features = features or self.features(camera)
        program = self.program(integrator, features, sampler)
        self._launched.add(self._program_key(integrator, features, sampler))
        seed = (settings.seed if seed is None else seed) & 0xFFFFFFFF
        return program, seed, settings.max_depth if max_depth is None else max_depth

    def steps_within(self, integrator: str, features: Features, seconds: float) -> int | None:
        """For an integrator whose passes are steps of whole-image iterations (sppm): how many of
        the next steps fit `seconds` at their measured costs; None for the others, or before
        anything was measured."""
        program = self.program(integrator, features, self.scene.render.sampler)
        if program.sliced or not hasattr(program, "steps_within"):
            return None
        return program.steps_within(seconds, self.slices_done, self.film.height)

    def is_sliced(self, integrator: str, features: Features, sampler: str = "independent") -> bool:
        """Whether the integrator's passes can be cut into pixel slices (all but sppm's)."""
        return self.program(integrator, features, sampler).sliced

    @property
    def samples_done(self) -> int:
        """Samples every pixel of the active region has (whole rounds)."""
        return self.slices_done // ROUND_SLICES

    @property
    def mean_spp(self) -> float:
        """Samples per pixel on average, a round in progress counted by its share of pixels (for
        interleaved slices their share of slices; bands of rows differ by a row)."""
        cursor = self.slices_done % ROUND_SLICES
        if cursor == 0 or self.round_order() == INTERLEAVED:
            return self.slices_done / ROUND_SLICES
        top, bottom = band_rows_array(bit_reverse_array(np.arange(cursor)), self.film.height)
        return self.samples_done + int((bottom - top).sum()) / self.film.height

    def focus_distance_at(self, camera: CameraFrame, u: float, v: float, integrator: str | None = None) -> float | None:
        """Distance along the view direction to the surface under (u, v) in [0,1]^2 (y up)."""
        hit = self.pick(camera, u, v, integrator)
        return hit.depth if hit is not None and hit.depth > 0 else None

    def pick(self, camera: CameraFrame, u: float, v: float, integrator: str | None = None) -> SurfaceHit | None:
        """What the camera ray through (u, v) in [0,1]^2 of the film (y up) meets first, or None."""
        program = self.program(integrator or self.scene.render.integrator, self.features(camera))
        window = self.film_window()  # (u, v) of the film, cast where it lies on the camera's image
        u, v = window.image_uv(u, v, self.film.width, self.film.height)
        floats, ints = self._pick_out
        program.pick(u, v, window.full_width, window.full_height, *camera.kernel_args()[:5], floats, ints)
        i, f = ints.to_numpy(), floats.to_numpy().astype(float)
        if i[0] != 1:
            return None
        return SurfaceHit(distance=float(f[0]), point=tuple(f[1:4]), normal=tuple(f[4:7]), uv=tuple(f[7:9]),
                          depth=float(f[9]), material=int(i[1]), primitive=int(i[2]), instance=int(i[3]),
                          front_face=bool(i[4]))

    def object_ids(self, camera: CameraFrame, integrator: str | None = None) -> np.ndarray:
        """The scene object each film pixel's centre shows (int32 (width, height), y up; -1: none)."""
        program = self.program(integrator or self.scene.render.integrator, self.features(camera))
        prims = np.empty((self.film.width, self.film.height), np.int32)
        program.hit_primitives(*self.film_window().kernel_args, *camera.kernel_args()[:5], prims)
        return self.geometry.objects_of(prims)

    def work_stats(self) -> dict:
        """Mean geometry work per ray (march steps on SDF scenes, BVH node visits on mesh scenes),
        primitive tests per ray (mesh scenes), and rays per sample."""
        totals = row_sums(self.work, self.film.width, self.film.height).sum(axis=0, dtype=np.float64)
        samples = max(1.0, self.mean_spp * self.film.width * self.film.height)
        rays = max(totals[2], 1.0)
        return {"work_per_ray": totals[0] / rays, "tests_per_ray": totals[1] / rays,
                "rays_per_sample": totals[2] / samples}

    def aov_images(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(albedo, normal) running means (H, W, 3), row 0 at the top; None unless the Renderer
        keeps AOVs and the integrator rendered writes them (zeros then)."""
        return self.aovs.images() if self.aovs is not None else None

    def image(self) -> np.ndarray:
        """The linear mean image (H, W, 3), row 0 at the top."""
        return self.film.mean_image()

    def shown_image(self) -> np.ndarray:
        """The linear image the viewer shows: the mean, with pixels a partial first round has not
        reached taken from their nearest sampled grid point (renderer/film/pixel_slices.py)."""
        film = self.film
        return filled_mean_array(film.mean_image(), film.sample_counts() + film.rejected_counts())

"""`sppm`: stochastic progressive photon mapping (Hachisuka and Jensen 2009), as in pbrt-v3's SPPM.

One call of `Renderer.render(camera, spp, integrator="sppm")` runs `spp` iterations; each is
  1. a camera pass: per pixel, a camera ray follows delta (mirror, smooth glass) and very glossy
     (GGX alpha < GLOSSY_ALPHA) bounces to the first diffuse or rough vertex, the *visible point*
     (VP). Emission seen along the way and direct light at the glossy vertices and at the VP are
     added to the pixel's direct sum, with the same light sampling and power-heuristic MIS as `mis`
     (one light sample and one BSDF sample per vertex); the VP keeps its position, normals, wo,
     shaded material and path throughput;
  2. a hash grid over the VPs (renderer/integrators/photon_grid.py), cells as large as the largest
     search radius, rebuilt on the device;
  3. a photon pass: `photons` photons (default: one per pixel of the image) leave the emitters
     (renderer/lights/photon_emission.py; most of them aimed at the region the camera sees) and follow BSDF samples with Russian roulette. At every hit
     after the first (the first one is direct light, which the camera pass took), on a surface
     that can hold VPs (diffuse or rough), every VP within its own radius of the hit receives
     phi += beta * f(wo_vp, wi) and M += 1 (atomics);
  4. a per-pixel update (Hachisuka and Jensen's progressive radius reduction):
        N' = N + alpha M,   R' = R sqrt(N' / (N + M)),   tau' = (tau + beta_vp phi) (R' / R)^2
     and the estimate  L = direct_sum / iterations + tau / (photons_emitted * pi * R^2),
     written to the film.

Radius. A pixel's radius is set once, at its first VP: `radius_pixels` pixel footprints at the
VP's distance along the camera path, clamped to [1/4, 4] times the geometric mean of that pass's
footprint radii, so that one far-away VP (a floor running to the horizon) cannot make the grid's
cells (the largest radius) huge for everybody else. From then on it only shrinks.

Depth. `max_depth` keeps Mitsuba's convention (path vertices, the emitter's included): emission at
camera vertex i counts if i <= max_depth, direct light at a VP of depth c if c + 1 <= max_depth,
and a photon's k-th hit (k >= 2) at a VP of depth c if c + k <= max_depth.

Samples. The camera pass draws like `mis` (the program's sampler, keyed by pixel and iteration,
dimension ids of renderer.sampling.dims). Photons draw from `photon_sampler` (Owen-scrambled Sobol
by default): a stream key no pixel uses, a photon index that runs on across iterations (so the
photons of all iterations are one low-discrepancy sequence per decision) and their own dimension
ids (dims.PHOTON_*), one per decision.

Film. An SPPM image is not the mean of independent samples, so the film holds the current
estimate as its mean, the iteration count as its sample count and +inf as its variance (unknown):
the viewer, screenshots and the command line show it like any image, and the HUD shows no noise
estimate for it (`noise_estimate = False`).

Thread-count independence. Every random number is a pure function of (photon or pixel, dimension,
seed); photon counts M and radii are integer or per-pixel arithmetic (and row-ordered reductions)
and come out identical whatever the threads; phi sums floats atomically, so its order (hence the
last bits) can vary.

GPU back-ends. The kernels compile and run on Vulkan. On Mesa's software Vulkan (lavapipe) with
Taichi 1.7.4, loops whose body holds an atomic lose iterations in some threads (reproduced without
SPPM), so there the photon deposits, which are atomics inside the query loop, come out low.

Known limits. Scenes with point, spot or directional lights are refused (they emit no photons
yet). A VP is the first diffuse or rough vertex: at a BSDF that has a delta part too (a
principled material with roughness 0: a mirror coat over a diffuse base), the light its delta part
reflects is not followed. Emitters that light sampling cannot sample (SDF shapes other than
spheres) emit no photons: their light reaches the image directly and through delta bounces only.
Participating media and analytic fog are not simulated (surfaces only; `null` boundaries are
crossed by camera and photon paths but block shadow rays), nor is dispersion. Glossy surfaces just
rough enough to hold VPs (alpha near GLOSSY_ALPHA) converge slowly. On SDF
scenes the environment's photons cover the camera and the typical visible distance (CORE_DISTANCE),
not the unbounded scene: environment light that reaches the image only by way of surfaces beyond
that is missed.
"""

import time
from dataclasses import dataclass

import numpy as np
import taichi as ti

from renderer.camera import generate_ray
from renderer.geometry.texture_footprint import footprint_shrink
from renderer.film.accumulation import is_finite_vec3
from renderer.geometry.interface import INF, Hit, Ray, Surface
from renderer.integrators.light_sampling import emission_weight, environment_weight, sample_direct
from renderer.integrators.photon_grid import PhotonGrid, bucket_of, cell_of, table_size_for
from renderer.integrators.tracer import MAX_VERTICES, RR_DEPTH
from renderer.materials.kinds import LobeFlags
from renderer.materials.table import Material
from renderer.film.pixel_slices import ROUND_SLICES
from renderer.program import RenderProgram
from renderer.sampling import dims
from renderer.sampling.warps import PI

vec3 = ti.math.vec3

# The photon stream's key: camera samples use pixel indices below 2^31, photons this plus the
# number of times their 32-bit index has wrapped.
PHOTON_STREAM = 0x80000000
# A pass's initial radii lie within [1/CLAMP, CLAMP] times the geometric mean of its footprint radii.
RADIUS_CLAMP = 4.0
# The photons' target region (renderer/lights/photon_emission.py, aiming) is the bounding sphere of the
# camera and the visible points up to this many times the geometric mean of their distances
# (footprints are proportional to distance); on SDF scenes, which have no finite bounds, it is also
# the sphere the environment's photons enter through. A floor running to the horizon would
# otherwise spread them over hundreds of metres, a few reaching the objects in view, each carrying
# a lot.
CORE_DISTANCE = 4.0
# Grid cells are this much wider than the largest radius, so that a VP within its radius of a
# photon lies strictly inside the photon's 3x3x3 block of cells, whatever the rounding of the two
# kernels that compute cells (build and query).
CELL_MARGIN = 1.0 + 1e-3
# Non-delta surfaces smoother than this GGX alpha (roughness ~0.3) are traced through by the camera
# pass instead of holding visible points: a photon density estimate over a radius of pixels cannot
# resolve a lobe that narrow (a chrome-like sphere would come out black and blotchy).
GLOSSY_ALPHA = 0.1
# |cos| below which a photon's direction is taken as tangent to the VP's surface (no estimate):
# f = eval / |cos| is then numerically meaningless.
MIN_COS = 1e-6
# An iteration in steps (SppmProgram.advance): as many as a round of pixel slices has, so a viewer
# frame's budget in slices is a budget in steps. The two phases' shares of an iteration differ by
# scene (Cornell box at 960x540: camera pass 178 ms, photons 1,576 ms; a glass scene the other
# way), and a frame planned from the cost of the steps before it runs long where a cheap phase
# gives way to a dear one (296 ms with half and half there). So each iteration splits its steps
# in proportion to the phases' measured times in the iteration before (half and half at first,
# MIN_PHASE_STEPS each at least), and the steps cost about the same throughout.
ITERATION_STEPS = ROUND_SLICES
MIN_PHASE_STEPS = 8


def _share(total: int, part: int, parts: int) -> tuple[int, int]:
    """[start, end) of the part-th of `parts` near-equal runs of range(total)."""
    return total * part // parts, total * (part + 1) // parts


@dataclass
class SppmOptions:
    """Knobs of `sppm` (data, not compile-time, except the photon sampler)."""

    photons: int | None = None  # photons per iteration; None = the active image's pixel count
    alpha: float = 2.0 / 3.0  # fraction of each pass's photons kept in N (Hachisuka and Jensen)
    radius_pixels: float = 2.0  # initial radius in pixel footprints at the visible point
    photon_sampler: str = "sobol"  # "sobol" | "independent"

    def __post_init__(self):
        if not 0.0 < self.alpha < 1.0:
            raise ValueError(f"sppm alpha must be in (0, 1), got {self.alpha}")
        if self.radius_pixels <= 0.0:
            raise ValueError(f"sppm radius_pixels must be positive, got {self.radius_pixels}")
        if self.photons is not None and self.photons < 1:
            raise ValueError(f"sppm photons must be positive, got {self.photons}")


def _synced_clock(sync: bool) -> float:
    """perf_counter after the device's work so far (0.0, and no wait, when not timing)."""
    if not sync:
        return 0.0
    ti.sync()
    return time.perf_counter()


@ti.data_oriented
class SppmState:
    """Per-pixel SPPM state at the film's maximum size (the active region is a kernel argument),
    shared by every SPPM program of a Renderer."""

    def __init__(self, max_width: int, max_height: int):
        self.max_height = max_height
        shape = (max_width, max_height)
        self.vp_p = ti.Vector.field(3, ti.f32, shape=shape)
        self.vp_n = ti.Vector.field(3, ti.f32, shape=shape)  # shading normal
        self.vp_ng = ti.Vector.field(3, ti.f32, shape=shape)
        self.vp_wo = ti.Vector.field(3, ti.f32, shape=shape)
        self.vp_beta = ti.Vector.field(3, ti.f32, shape=shape)
        self.vp_mat = Material.field(shape=shape)
        self.vp_depth = ti.field(ti.i32, shape=shape)  # path vertices up to the VP; 0 = no VP this pass
        # The grid cell the VP was filed under. Queries compare with this rather than recompute it:
        # two kernels may round (q - lo) / cell differently (a GPU compiler may turn the division
        # into a reciprocal in one and not the other), and a VP would then be missed.
        self.vp_cell = ti.Vector.field(3, ti.i32, shape=shape)
        self.footprint = ti.field(ti.f32, shape=shape)  # this pass's candidate initial radius
        self.radius = ti.field(ti.f32, shape=shape)  # 0 until the pixel's first VP
        self.n = ti.field(ti.f32, shape=shape)
        self.m = ti.field(ti.i32, shape=shape)
        self.phi = ti.Vector.field(3, ti.f32, shape=shape)
        self.tau = ti.Vector.field(3, ti.f32, shape=shape)
        self.direct = ti.Vector.field(3, ti.f32, shape=shape)  # sum over passes
        self.grid = PhotonGrid(max_width * max_height)
        # lo, hi of the VPs and the camera (the photon grid's box)
        self.box = ti.Vector.field(3, ti.f32, shape=2)
        # [0] cell size (largest radius), [1] sum of log footprint radii, [2] their count
        self.scalars = ti.field(ti.f32, shape=3)
        # per-row partial reductions: [log footprint sum, VP count, largest radius, -] and boxes
        # [lo, hi, core lo, core hi]
        self.row_stats = ti.Vector.field(4, ti.f32, shape=max_height)
        self.row_box = ti.Vector.field(3, ti.f32, shape=(max_height, 4))
        self.photons_emitted = 0  # over all passes since the last clear
        self.iterations = 0
        self.next_step = None  # the first step a continuing render passes (SppmProgram.advance)
        self.camera_steps = ITERATION_STEPS // 2  # this iteration's split (see ITERATION_STEPS)
        self.phase_seconds = [0.0, 0.0]  # measured seconds of each phase's steps, or 0
        # measured seconds of what each phase's last step does besides: the camera pass's
        # statistics and photon grid (10-20 ms at 960x540 on a 2-core CPU), the update (2-3 ms)
        self.finish_seconds = [0.0, 0.0]
        # measured seconds of each row of the camera pass (nan: not yet): rows differ severalfold
        # (a band of mirrors against one of sky), and while the view is still the last iteration's
        # rows predict the next one's
        self.row_seconds = np.full(max_height, np.nan)

    @ti.kernel
    def clear(self):
        for x, y in self.radius:
            self.radius[x, y] = 0.0
            self.n[x, y] = 0.0
            self.m[x, y] = 0
            self.phi[x, y] = vec3(0.0)
            self.tau[x, y] = vec3(0.0)
            self.direct[x, y] = vec3(0.0)
            self.vp_depth[x, y] = 0

    def time_phase(self, phase: int, seconds: float, steps_done: int, camera_steps: int) -> None:
        """`steps_done` steps of `phase` (0 camera, 1 photons) took `seconds`: the phase's whole
        work is that per step times its steps (a running estimate, the newest weighing half)."""
        phase_steps = camera_steps if phase == 0 else ITERATION_STEPS - camera_steps
        whole = seconds / max(steps_done, 1) * phase_steps
        old = self.phase_seconds[phase]
        self.phase_seconds[phase] = whole if old == 0.0 else 0.5 * (old + whole)

    def time_rows(self, first: int, end: int, seconds: float) -> None:
        if end > first:
            self.row_seconds[first:end] = seconds / (end - first)

    def band_seconds(self, first: int, end: int) -> float | None:
        """Predicted seconds of camera rows [first, end), None if a row was not measured."""
        rows = self.row_seconds[first:end]
        return None if np.isnan(rows).any() else float(rows.sum())

    def time_finish(self, phase: int, seconds: float) -> None:
        old = self.finish_seconds[phase]
        self.finish_seconds[phase] = seconds if old == 0.0 else 0.5 * (old + seconds)

    def next_camera_steps(self) -> int:
        """Steps for the camera rows in the next iteration: in proportion to the phases' times."""
        camera, photons = (p + f for p, f in zip(self.phase_seconds, self.finish_seconds))
        if self.phase_seconds[0] <= 0.0 or self.phase_seconds[1] <= 0.0:
            return self.camera_steps
        share = round(ITERATION_STEPS * camera / (camera + photons))
        return min(max(share, MIN_PHASE_STEPS), ITERATION_STEPS - MIN_PHASE_STEPS)

    def steps_within(self, seconds: float, first_step: int, height: int,
                     limit: int = 4 * ITERATION_STEPS) -> int | None:
        """How many steps from `first_step` fit in `seconds` at the measured costs (at least one,
        at most `limit`), the finishing work of a phase's last step counted where it falls; None
        before both phases were timed. A frame then stops short of a dear last step it could not
        afford, rather than overrunning by it."""
        if min(self.phase_seconds) <= 0.0:
            return None
        cameras = self.camera_steps if first_step % ITERATION_STEPS else self.next_camera_steps()
        spent, count = 0.0, 0
        while count < limit:
            part = (first_step + count) % ITERATION_STEPS
            if part == 0 and count:
                cameras = self.next_camera_steps()
            phase = 0 if part < cameras else 1
            phase_steps = cameras if phase == 0 else ITERATION_STEPS - cameras
            cost = self.phase_seconds[phase] / max(phase_steps, 1)
            if phase == 0:
                band = self.band_seconds(*_share(height, part, cameras))
                cost = cost if band is None else band
            if part == (cameras - 1 if phase == 0 else ITERATION_STEPS - 1):
                cost += self.finish_seconds[phase]
            if count and spent + cost > seconds:
                break
            spent += cost
            count += 1
        # A frame that reaches past this iteration ends on an iteration's end: the image changes
        # when one completes, and the frames after start whole iterations.
        to_end = -first_step % ITERATION_STEPS or ITERATION_STEPS
        if count > to_end:
            count = to_end + (count - to_end) // ITERATION_STEPS * ITERATION_STEPS
        return count

    def reset(self) -> None:
        self.clear()
        self.photons_emitted = 0
        self.iterations = 0
        self.next_step = None

    # --- host views (tests) ------------------------------------------------------------------------
    def _active(self, field, width, height):
        return np.ascontiguousarray(field.to_numpy()[:width, :height].swapaxes(0, 1)[::-1])

    def radii(self, width: int, height: int) -> np.ndarray:
        """Per-pixel radius (H, W), row 0 at the top."""
        return self._active(self.radius, width, height)

    def photon_counts(self, width: int, height: int) -> np.ndarray:
        """Per-pixel N, the progressive photon count (H, W)."""
        return self._active(self.n, width, height)

    def tau_image(self, width: int, height: int) -> np.ndarray:
        return self._active(self.tau, width, height)


@ti.data_oriented
class SppmProgram(RenderProgram):
    """The kernels of one (geometry, Features, sampler) combination; the state is the Renderer's."""

    sliced = False  # an iteration traces photons for the whole image: passes are whole iterations

    def __init__(self, geometry, materials, environment, integrator, film, work, features, sampler, lights,
                 state: SppmState, emission, photon_sampler, options: dict):
        super().__init__(geometry, materials, environment, integrator, film, work, features, sampler, lights)
        self.state = state
        self.grid = state.grid
        self.emission = emission
        self.photon_sampler = photon_sampler
        self.options = options  # the Renderer's integrator_options (read at every render call)

    def current_options(self) -> SppmOptions:
        return self.options.get("sppm") or SppmOptions()

    # --- the passes ------------------------------------------------------------------------------------
    # An iteration is ITERATION_STEPS steps, so that a viewer frame can take a share of one (the
    # passes of the other integrators are cut into pixel slices; SPPM's photons need every VP):
    # `camera_steps` bands of rows of the camera pass (the last one also makes the pass's
    # statistics and the photon grid), then the photons in the other steps' equal runs (the last one
    # also makes the update). A photon's random numbers depend only on its index, so an
    # iteration in steps traces the same paths as one in a piece.
    def steps_within(self, seconds: float, first_step: int, height: int) -> int | None:
        """Steps from `first_step` that fit `seconds` at this state's measured costs (SppmState)."""
        return self.state.steps_within(seconds, first_step, height)

    def advance(self, width, height, steps, first_step, seed, max_depth, origin, forward, right, up, half_height,
                aperture, focus, window=None):
        """Steps [first_step, first_step + steps) of the iterations (step k is step k % ITERATION_STEPS
        of iteration k // ITERATION_STEPS); the state must have ended at first_step, or first_step
        starts an iteration (anything else is refused: the steps in between are lost). `window`:
        where the film lies on the camera's image (renderer/film/crop_window.py; None: the film is
        the image)."""
        state = self.state
        options = self.current_options()
        if options.photon_sampler != self.photon_sampler.name:
            raise ValueError(f"sppm: the photon sampler is chosen when the program is built "
                             f"('{self.photon_sampler.name}'); use a new Renderer for '{options.photon_sampler}'")
        if first_step == 0 or state.next_step != first_step:
            if first_step % ITERATION_STEPS:
                raise ValueError(f"sppm: step {first_step} does not continue this state (at {state.next_step})")
            state.reset()
        photons = options.photons or width * height
        table = table_size_for(width * height)
        camera = (origin, forward, right, up, half_height, aperture, focus,
                  *(window.kernel_args if window is not None else (width, height, 0, 0)))
        step, end = first_step, first_step + steps
        while step < end:  # consecutive steps of one phase in one launch
            index, part = divmod(step, ITERATION_STEPS)
            iteration_start = index * ITERATION_STEPS
            if part == 0:
                state.camera_steps = state.next_camera_steps()
            cameras = state.camera_steps
            timed = steps < ITERATION_STEPS  # steps of a frame: time the phases for the next split
            t0 = time.perf_counter()
            finish = 0.0
            if part < cameras:
                last = min(end - iteration_start, cameras)
                rows = _share(height, part, cameras)[0], _share(height, last - 1, cameras)[1]
                if rows[1] > rows[0]:
                    self.camera_rows(width, height, *rows, index, seed, max_depth, options.radius_pixels, *camera)
                    if timed:
                        state.time_rows(*rows, _synced_clock(True) - t0)
                if last == cameras:
                    finish = _synced_clock(timed)
                    self.camera_statistics(width, height, origin)
                    self.build_grid(width, height, table)
                    finish = _synced_clock(timed) - finish
                phase = 0
            else:
                last = min(end - iteration_start, ITERATION_STEPS)
                runs = ITERATION_STEPS - cameras
                start = _share(photons, part - cameras, runs)[0]
                stop = _share(photons, last - 1 - cameras, runs)[1]
                if self.emission.emits and stop > start:
                    base = state.photons_emitted + start
                    self.photon_pass(stop - start, base & 0xFFFFFFFF, (base >> 32) & 0x7FFFFFFF, seed, max_depth,
                                     table - 1)
                if last == ITERATION_STEPS:
                    state.photons_emitted += photons
                    state.iterations = index + 1
                    finish = _synced_clock(timed)
                    self.update(width, height, options.alpha, float(state.photons_emitted), state.iterations)
                    finish = _synced_clock(timed) - finish
                phase = 1
            if timed:
                total = _synced_clock(True) - t0
                state.time_phase(phase, total - finish, last - part, cameras)
                whole_pass = state.band_seconds(0, height) if phase == 0 else None
                if whole_pass is not None:  # every row measured: the camera pass is their sum
                    state.phase_seconds[0] = whole_pass
                if finish > 0.0:
                    state.time_finish(phase, finish)
            step = iteration_start + last
        state.next_step = first_step + steps
        return steps

    @ti.kernel
    def camera_rows(self, width: ti.i32, height: ti.i32, row_first: ti.i32, row_end: ti.i32, index: ti.i32,
                    seed: ti.u32, max_depth: ti.i32, radius_pixels: ti.f32, origin: ti.math.vec3,
                    forward: ti.math.vec3, right: ti.math.vec3, up: ti.math.vec3, half_height: ti.f32,
                    aperture: ti.f32, focus: ti.f32, full_width: ti.i32, full_height: ti.i32, window_x: ti.i32,
                    window_y: ti.i32):
        """The camera pass's paths for rows [row_first, row_end) (a whole pass: 0, height); the
        film's pixel (x, y) is the image's (x + window_x, y + window_y) (a crop window)."""
        st = self.state
        for x, y in ti.ndrange(width, (row_first, row_end)):
            pixel = (y + window_y) * full_width + x + window_x
            sample = self.sampler.start(pixel, index, seed)
            # (The box filter: SPPM's visible points gather per pixel; Renderer warns of another filter.)
            ray = generate_ray(x + window_x, y + window_y, full_width, full_height,
                               self.sampler.get2d(sample, dims.PIXEL), self.sampler, sample,
                               origin, forward, right, up, half_height, aperture, focus,
                               self.features.depth_of_field, self.features.orthographic)
            radius = radius_pixels
            if ti.static(self.filters_textures):
                # Textures filtered over a cone that narrows with the iterations, as camera samples'
                # (renderer/program.py); the photon radius keeps the whole pixel's footprint.
                shrink = footprint_shrink(index)
                ray.cone_width *= shrink
                ray.cone_spread *= shrink
                radius = radius_pixels / shrink
            value, stats = self._trace_camera(x, y, ray, sample, max_depth, radius)
            # Plain stores, not +=: on a global field += compiles to an atomic add, and each pixel
            # has one writer here.
            if is_finite_vec3(value):
                st.direct[x, y] = st.direct[x, y] + value
            else:
                self.film.rejected[x, y] = self.film.rejected[x, y] + 1
            self.work[x, y] = self.work[x, y] + stats

    @ti.kernel
    def camera_statistics(self, width: ti.i32, height: ti.i32, origin: ti.math.vec3):
        """Once every row of the camera pass is traced."""
        st = self.state
        # The pass's statistics: the geometric mean of the footprint radii, the VPs' box (with the
        # camera, for the environment's photons on SDF scenes), then initial radii and the cell
        # size. Rows in parallel, each reduced in a local variable, then the rows in order: no
        # atomics, and a float sum whose order (hence value) does not depend on the thread count,
        # so initial radii are the same bits however many threads run.
        for y in range(height):
            total = 0.0
            count = 0.0
            lo = vec3(INF)
            hi = vec3(-INF)
            for x in range(width):
                if st.vp_depth[x, y] > 0:
                    total += ti.log(st.footprint[x, y])
                    count += 1.0
                    lo = ti.min(lo, st.vp_p[x, y])
                    hi = ti.max(hi, st.vp_p[x, y])
            st.row_stats[y] = ti.math.vec4(total, count, 0.0, 0.0)
            st.row_box[y, 0] = lo
            st.row_box[y, 1] = hi
        for _ in range(1):
            sums = ti.math.vec4(0.0)
            lo = origin
            hi = origin
            for y in range(height):
                sums += st.row_stats[y]
                lo = ti.min(lo, st.row_box[y, 0])
                hi = ti.max(hi, st.row_box[y, 1])
            st.scalars[1] = sums.x
            st.scalars[2] = sums.y
            st.box[0] = lo
            st.box[1] = hi
        for y in range(height):
            largest = 0.0
            lo = vec3(INF)
            hi = vec3(-INF)
            mean = ti.exp(st.scalars[1] / ti.max(st.scalars[2], 1.0))
            for x in range(width):
                if st.vp_depth[x, y] > 0:
                    if st.radius[x, y] == 0.0:
                        st.radius[x, y] = ti.math.clamp(st.footprint[x, y], mean / RADIUS_CLAMP,
                                                        mean * RADIUS_CLAMP)
                    largest = ti.max(largest, st.radius[x, y])
                    if st.footprint[x, y] <= mean * CORE_DISTANCE:
                        lo = ti.min(lo, st.vp_p[x, y])
                        hi = ti.max(hi, st.vp_p[x, y])
            st.row_stats[y].z = largest
            st.row_box[y, 2] = lo
            st.row_box[y, 3] = hi
        for _ in range(1):
            largest = 0.0
            lo = origin
            hi = origin
            for y in range(height):
                largest = ti.max(largest, st.row_stats[y].z)
                lo = ti.min(lo, st.row_box[y, 2])
                hi = ti.max(hi, st.row_box[y, 3])
            st.scalars[0] = largest
            if ti.static(self.emission.bounds_per_pass):
                self.emission.set_bounds_func(lo, hi)
            self.emission.set_target_func(lo, hi)

    @ti.func
    def _trace_camera(self, x, y, ray_in, sample, max_depth, radius_pixels):
        """Emission and direct light along the camera path to the VP; stores the VP.

        As in `mis`, every ray (camera, delta bounces, the VP's shadow ray and its BSDF sample)
        is traced at one call site of the geometry: a pending shadow ray is traced by the next
        iteration, the BSDF-sampled ray by the one after."""
        st = self.state
        lights = self.lights
        st.vp_depth[x, y] = 0
        radiance = vec3(0.0)
        beta = vec3(1.0)
        stats = vec3(0.0)
        ray = ray_in
        length = 0.0  # camera path length to the current vertex (for the pixel footprint)
        probing = 0  # 1 once the ray is the VP's BSDF sample (direct light only, then the path ends)
        prev_p = ray.o
        prev_n = vec3(0.0)
        prev_pdf = 0.0
        prev_delta = 1  # the camera and delta bounces: what they find is not light-sampled
        s = Surface(p=ray.o, n_geo=vec3(0.0, 0.0, 1.0), n_shading=vec3(0.0, 0.0, 1.0), uv=ti.math.vec2(0.0),
                    uv1=ti.math.vec2(0.0), tangent=ti.math.vec4(0.0), material=0, prim=-1, front_face=1, eps=0.0,
                    cone_width=0.0, cone_spread=0.0)
        next_dir = ray.d
        shadow_pending = False
        shadow_target = vec3(0.0)
        shadow_n = vec3(0.0)
        shadow_value = vec3(0.0)
        ending = False  # the path is over once its pending shadow ray is traced
        depth = 0
        for _ in range(2 * MAX_VERTICES):
            t_max = INF
            if depth > 0:
                ray, t_max = self.geometry.next_segment(s, next_dir, shadow_target, shadow_n, shadow_pending)
            hit = Hit(hit=0, t=t_max, work=0, tests=0, inside=0, prim=-1, bary=ti.math.vec2(0.0))
            if t_max > 0.0:
                hit = self.geometry.trace(ray, t_max, shadow_pending)  # a shadow ray stops at any hit
                stats += vec3(hit.work, hit.tests, 1.0)
            if shadow_pending:
                if hit.hit == 0:
                    radiance += shadow_value
                shadow_pending = False
                if ending:
                    break
                continue
            if hit.hit == 0:
                weight = environment_weight(lights, True, prev_delta, prev_pdf, ray.d)
                radiance += beta * weight * self.environment.radiance(ray.d)
                break
            s = self.geometry.surface(ray, hit)
            wo = -ray.d
            mat, n = self.bsdf.shade(s, wo)
            if ti.static(self.features.has_emission):
                if (s.front_face == 1 or mat.two_sided_emission == 1) and mat.emission.max() > 0.0:
                    weight = emission_weight(lights, True, prev_delta, prev_pdf, prev_p, prev_n, s)
                    radiance += beta * weight * mat.emission
            if probing == 1:
                break
            length += hit.t
            if max_depth >= 0 and depth + 1 >= max_depth:
                break
            dim = dims.BOUNCE_BASE + dims.PER_BOUNCE * depth
            if self.bsdf.has_smooth_part(mat):
                if self._gathers(mat):
                    st.vp_p[x, y] = s.p
                    st.vp_n[x, y] = n
                    st.vp_ng[x, y] = s.n_geo
                    st.vp_wo[x, y] = wo
                    st.vp_beta[x, y] = beta
                    st.vp_mat[x, y] = mat
                    st.vp_depth[x, y] = depth + 1
                    st.footprint[x, y] = radius_pixels * ti.max(ray_in.cone_width + length * ray_in.cone_spread,
                                                                1e-7)
                    probing = 1
                # Direct light at the VP, and at the glossy vertices traced through on the way.
                found, ls, f, scale = sample_direct(self, True, mat, n, s, wo,
                                                    self.sampler.get1d(sample, dim + dims.LIGHT_SELECT),
                                                    self.sampler.get2d(sample, dim + dims.LIGHT_POINT))
                if found:
                    shadow_pending = True
                    shadow_target = ls.p
                    shadow_n = ls.n
                    shadow_value = beta * f * ls.radiance * scale
            bs = self.bsdf.sample_at(mat, n, s.n_geo, wo, self.sampler.get1d(sample, dim + dims.BSDF_LOBE),
                                     self.sampler.get2d(sample, dim + dims.BSDF_DIRECTION))
            if bs.valid == 0:
                ending = True
            else:
                beta *= bs.weight
                prev_p = s.p
                prev_n = n
                prev_pdf = bs.pdf
                prev_delta = bs.delta
                if probing == 0 and depth >= RR_DEPTH:
                    q = ti.min(beta.max(), 0.95)
                    if self.sampler.get1d(sample, dim + dims.ROULETTE) >= q:
                        ending = True
                    else:
                        beta /= q
                next_dir = bs.wi
            if ending and not shadow_pending:
                break
            depth += 1
        return radiance, stats

    @ti.func
    def _gathers(self, mat):
        """Whether a surface keeps visible points and receives photons: diffuse, or rough enough
        (GLOSSY_ALPHA) for a density estimate over the search radius to see its lobe. Smoother
        non-delta surfaces are traced through by the camera pass, like mirrors (pbrt-v3's rule
        for glossy BSDFs), with direct light taken at each of them."""
        flags = self.bsdf.flags(mat)
        keep = mat.alpha >= GLOSSY_ALPHA or (flags & LobeFlags.DIFFUSE) != 0
        return keep and (flags & LobeFlags.NON_DELTA) != 0

    @ti.kernel
    def build_grid(self, width: ti.i32, height: ti.i32, table_size: ti.i32):
        st = self.state
        grid = self.grid
        mask = table_size - 1
        cell = st.scalars[0] * CELL_MARGIN
        inv_cell = 1.0 / ti.max(cell, 1e-30)
        lo = st.box[0]
        grid.clear(table_size)
        for x, y in ti.ndrange(width, height):
            if self._in_grid(x, y):
                c = cell_of(st.vp_p[x, y], lo, inv_cell)
                st.vp_cell[x, y] = c
                ti.atomic_add(grid.count[bucket_of(c, mask)], 1)
        grid.scan(table_size)
        for x, y in ti.ndrange(width, height):
            if self._in_grid(x, y):
                h = bucket_of(st.vp_cell[x, y], mask)
                slot = grid.start[h] + ti.atomic_add(grid.count[h], 1)
                grid.entries[slot] = x * self.state.max_height + y

    @ti.func
    def _in_grid(self, x, y):
        return self.state.vp_depth[x, y] > 0 and self.state.vp_beta[x, y].max() > 0.0

    @ti.kernel
    def photon_pass(self, count: ti.i32, base: ti.u32, epoch: ti.u32, seed: ti.u32, max_depth: ti.i32,
                    mask: ti.i32):
        for i in range(count):
            index = base + ti.cast(i, ti.u32)
            stream = ti.u32(PHOTON_STREAM) + epoch + (ti.u32(1) if index < base else ti.u32(0))
            sample = self.photon_sampler.start(stream, index, seed)
            self._trace_photon(sample, max_depth, mask)

    @ti.func
    def _trace_photon(self, sample, max_depth, mask):
        ps = self.photon_sampler
        em = self.emission.sample(self, ps.get1d(sample, dims.PHOTON_LIGHT_SELECT),
                                  ps.get2d(sample, dims.PHOTON_LIGHT_POINT), ps.get2d(sample, dims.PHOTON_DIRECTION),
                                  ps.get1d(sample, dims.PHOTON_AIM))
        if em.valid == 1 and em.beta.max() > 0.0:
            beta = em.beta
            s = em.surface
            d = em.d
            for bounce in range(MAX_VERTICES):
                k = bounce + 1  # index of the hit this ray finds
                ray = Ray(o=em.o, d=d, cone_width=0.0, cone_spread=0.0)
                if bounce > 0 or em.from_env == 0:
                    ray = self.geometry.spawn(s, d)
                hit = self.geometry.intersect(ray, INF)
                if hit.hit == 0:
                    break
                s = self.geometry.surface(ray, hit)
                wo = -ray.d
                mat, n = self.bsdf.shade(s, wo)
                if k >= 2 and self._gathers(mat):
                    self._deposit(s.p, wo, beta, k, max_depth, mask)
                # The next hit, k + 1, could only count for a VP at depth >= 1: k + 2 <= max_depth.
                if max_depth >= 0 and k + 2 > max_depth:
                    break
                dim = dims.PHOTON_BOUNCE_BASE + dims.PHOTON_PER_BOUNCE * bounce
                bs = self.bsdf.sample_at(mat, n, s.n_geo, wo, ps.get1d(sample, dim + dims.BSDF_LOBE),
                                         ps.get2d(sample, dim + dims.BSDF_DIRECTION))
                if bs.valid == 0:
                    break
                weight = bs.weight * self._adjoint_factor(mat, n, s.n_geo, wo, bs.wi)
                new_beta = beta * weight
                # Russian roulette by the throughput's change (pbrt): photons keep their power.
                survive = ti.min(1.0, new_beta.max() / beta.max())
                if ps.get1d(sample, dim + dims.ROULETTE) >= survive:
                    break
                beta = new_beta / survive
                d = bs.wi

    @ti.func
    def _adjoint_factor(self, mat, n, ng, wo, wi):
        """What turns the BSDF's radiance-transport weight into the photon's (importance transport,
        Veach 1997 5.2-5.3): shading normals make f non-symmetric, |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|),
        and refraction's 1 / eta^2 radiance scaling does not apply to photons."""
        factor = 1.0
        num = ti.abs(wo.dot(n)) * ti.abs(wi.dot(ng))
        den = ti.abs(wo.dot(ng)) * ti.abs(wi.dot(n))
        if den > 0.0:
            factor = num / den
        else:
            factor = 0.0
        if ti.static(len(self.bsdf.refracting) > 0):
            if self.bsdf.refracts(mat, ng, wo, wi):
                eta = mat.ior if n.dot(wo) >= 0.0 else 1.0 / mat.ior
                factor *= eta * eta
        return factor

    @ti.func
    def _deposit(self, p, wi, beta, k, max_depth, mask):
        """Adds the photon at p (arriving from direction wi) to every VP within that VP's radius."""
        st = self.state
        grid = self.grid
        cell = st.scalars[0] * CELL_MARGIN
        lo = st.box[0]
        hi = st.box[1]
        if cell > 0.0 and (p >= lo - cell).all() and (p <= hi + cell).all():
            inv_cell = 1.0 / cell
            first = cell_of(p - cell, lo, inv_cell)
            last = cell_of(p + cell, lo, inv_cell)
            for j in range(27):  # a loop, not unrolled: its body (a BSDF evaluation) compiles once
                c = first + ti.math.ivec3(j % 3, (j // 3) % 3, j // 9)
                if (c <= last).all():
                    h = bucket_of(c, mask)
                    for e in range(grid.start[h], grid.start[h + 1]):
                        pix = grid.entries[e]
                        x = pix // self.state.max_height
                        y = pix % self.state.max_height
                        q = st.vp_p[x, y]
                        r = st.radius[x, y]
                        to = q - p
                        if to.dot(to) <= r * r and (st.vp_cell[x, y] == c).all():
                            if max_depth < 0 or st.vp_depth[x, y] + k <= max_depth:
                                ti.atomic_add(st.m[x, y], 1)
                                vn = st.vp_n[x, y]
                                cos = ti.abs(wi.dot(vn))
                                if cos > MIN_COS:
                                    f, _ = self.bsdf.eval_at(st.vp_mat[x, y], vn, st.vp_ng[x, y], st.vp_wo[x, y], wi)
                                    if f.max() > 0.0:
                                        ti.atomic_add(st.phi[x, y], beta * (f / cos))

    @ti.kernel
    def update(self, width: ti.i32, height: ti.i32, alpha: ti.f32, photons_emitted: ti.f32, iterations: ti.i32):
        st = self.state
        for x, y in ti.ndrange(width, height):
            m = st.m[x, y]
            r = st.radius[x, y]
            if m > 0 and r > 0.0:
                n_old = st.n[x, y]
                n_new = n_old + alpha * ti.cast(m, ti.f32)
                r_new = r * ti.sqrt(n_new / (n_old + ti.cast(m, ti.f32)))
                st.tau[x, y] = (st.tau[x, y] + st.vp_beta[x, y] * st.phi[x, y]) * ((r_new / r) * (r_new / r))
                st.n[x, y] = n_new
                st.radius[x, y] = r_new
            st.m[x, y] = 0
            st.phi[x, y] = vec3(0.0)
            value = st.direct[x, y] / ti.cast(iterations, ti.f32)
            r = st.radius[x, y]
            if r > 0.0 and photons_emitted > 0.0:
                value += st.tau[x, y] / (photons_emitted * PI * r * r)
            self.film.set_estimate(x, y, value, iterations)


@ti.data_oriented
class StochasticProgressivePhotonMapping:
    name = "sppm"
    hotkey = "m"  # "photon map"
    description = "stochastic progressive photon mapping: light paths for caustics, biased but consistent"
    display_tonemapper = None
    uses_lights = True
    noise_estimate = False  # the film holds an estimate, not a mean of samples: no variance
    writes_aovs = False  # (its camera pass could; until then it is denoised from its colour alone)
    denoisable = True

    def make_program(self, renderer, features, sampler, lights):
        from renderer.sampling.sampler import make_sampler

        if renderer.scene.lights:
            # Their direct light would be right, but without photons the indirect light is missing.
            raise ValueError("sppm: point, spot and directional lights emit no photons yet; render this scene "
                             "with mis or nee")

        options = renderer.integrator_options.get("sppm") or SppmOptions()
        state = renderer.shared("sppm_state", lambda: SppmState(renderer.film.max_width, renderer.film.max_height))
        emission = renderer.shared("photon_emission", lambda: _emission_for(renderer, lights))
        return SppmProgram(renderer.geometry, renderer.materials, renderer.environment, self, renderer.film,
                           renderer.work, features, sampler, lights, state, emission,
                           make_sampler(options.photon_sampler), renderer.integrator_options)


def _emission_for(renderer, lights):
    from renderer.lights.photon_emission import Emission

    bounds = None
    data = getattr(renderer.geometry, "data", None)
    if renderer.scene.geometry == "mesh" and data is not None and data.primitive_count:
        bounds = data.scene_bounds()
    return Emission(renderer.geometry, lights, renderer.scene.environment, bounds)


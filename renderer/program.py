"""One compiled rendering program: a (geometry, integrator, Features) combination and its kernels.

Taichi compiles a data-oriented object's kernels once per instance, so a RenderProgram *is* the
kernel cache entry: the Renderer keeps one per (integrator, Features) and switching back to a
combination already seen compiles nothing.
"""
import taichi as ti

from renderer.film.adaptive import STOPPED
from renderer.film.aovs import FEATURE_BOOSTED_SAMPLES, FEATURE_SEED_SALT
from renderer.camera import generate_ray, pinhole_ray
from renderer.geometry.interface import INF, Ray
from renderer.geometry.texture_footprint import footprint_shrink
from renderer.materials.bsdf import Bsdf
from renderer.film.pixel_filter import pixel_sample
from renderer.film.band_table import pass_layout, pass_pixel
from renderer.film.pixel_slices import BANDS, ROUND_SLICES
from renderer.sampling import dims


@ti.data_oriented
class RenderProgram:
    def __init__(self, geometry, materials, environment, integrator, film, work, features, sampler, lights=None,
                 media=None, aovs=None, bands=None, feature_samples=False):
        self.geometry = geometry
        self.media = media  # MediaTable (read only by kernels compiled with media or fog)
        self.lights = lights  # None for integrators that do not sample lights
        self.sampler = sampler
        self.bsdf = Bsdf(materials, features)
        self.environment = environment
        self.integrator = integrator
        self.film = film
        self.bands = bands  # the film's BandTable (renderer/film/band_table.py); None: no band passes (sppm)
        self.work = work  # per-pixel [geometry work, primitive tests, rays traced] summed over samples
        self.features = features
        # Denoising AOVs are written where the renderer keeps them and the integrator has them.
        self.aovs = aovs if getattr(integrator, "writes_aovs", False) else None
        self.writes_aovs = self.aovs is not None  # (a Python bool: `is` is not Taichi syntax)
        # Integrators with AOVs can trace feature samples: their li takes a features_only flag.
        self.feature_tracing = getattr(integrator, "writes_aovs", False)
        # The feature-sample loop is compiled in only where asked for (Renderer.program: scenes
        # with texture or normal maps): unused, it cost the sample loop 2.5% and its compile 5-9%.
        self.feature_samples = self.writes_aovs and feature_samples
        # Mip-mapped textures (mesh geometry only): each camera ray's cone narrows with its sample index.
        self.filters_textures = getattr(geometry, "filters_textures", False)

    # A pass over slices samples its pixels in slice order (renderer/film/pixel_slices.py); the rounds a
    # film has seen are in its counts, so the whole-image passes of SPPM do not apply.
    sliced = True

    def render(self, width: int, height: int, spp: int, slice_first: int, slice_count: int, order: int,
               *rest, feature_boost: int = 0, window=None) -> None:
        """`spp` samples for each pixel of slices [slice_first, slice_first + slice_count) of a round
        cut in `order` (pixel_slices: INTERLEAVED or BANDS); `rest`: seed, max depth and the
        camera's kernel arguments. `feature_boost`: the AOV-only samples each of a pixel's first
        colour samples brings where AOVs are kept (renderer/film/aovs.py). A partial band pass first
        fills the band table for `height` (nothing to do when it already is: a still view's
        passes; moving frames, which change the height, are interleaved). `window`: where the film
        lies on the camera's image (renderer/film/crop_window.py; None: the film is the image)."""
        if feature_boost > 0 and not self.feature_samples:
            raise ValueError("feature samples asked of a program compiled without them (Renderer.program)")
        if order == BANDS and slice_count < ROUND_SLICES:
            self.bands.set_height(height)
        window_args = window.kernel_args if window is not None else (width, height, 0, 0)
        self._render(width, height, spp, slice_first, slice_count, order, feature_boost, *rest, *window_args)

    @ti.kernel
    def _render(self, width: ti.i32, height: ti.i32, spp: ti.i32, slice_first: ti.i32, slice_count: ti.i32,
                order: ti.i32, feature_boost: ti.i32, seed: ti.u32, max_depth: ti.i32, origin: ti.math.vec3, forward: ti.math.vec3,
                right: ti.math.vec3, up: ti.math.vec3, half_height: ti.f32, aperture: ti.f32, focus: ti.f32,
                full_width: ti.i32, full_height: ti.i32, window_x: ti.i32, window_y: ti.i32):
        banded, layout, n = pass_layout(self.bands, slice_first, slice_count, width, height, order)
        # Threads take the loop's blocks as they finish (renderer/arch.cpu_scheduling_options), so
        # a pass's dear and cheap pixels are shared among them whatever their order.
        for i in range(n):
            x, y = pass_pixel(self.bands, i, banded, slice_first, slice_count, width, height, order, layout)
            if x < width and y < height:
                # A pixel adaptive sampling has stopped (renderer/film/adaptive.py) takes no more samples;
                # a nested test: Taichi's `and` evaluates both sides, and (x, y) may lie outside the film.
                if self.film.adaptive[x, y] != STOPPED:
                    # The image's pixel (a crop window's film starts inside the image): its number
                    # seeds the pixel's random numbers, so a crop renders the whole image's pixels.
                    pixel = (y + window_y) * full_width + x + window_x
                    # The pixel's own sample count is its next sample index (see pixel_slices).
                    first_sample = self.film.count[x, y] + self.film.rejected[x, y]
                    work = ti.math.vec3(0.0)
                    for s in range(spp):
                        index = first_sample + s
                        if ti.static(self.feature_samples):
                            # Camera sample 0 is the colour sample; any more are feature samples,
                            # which only find the AOVs (renderer/film/aovs.py), on streams of their own.
                            features = ti.select(index < FEATURE_BOOSTED_SAMPLES, feature_boost, 0)
                            for k in range(1 + features):
                                stream_index, stream_seed = index, seed
                                if k > 0:
                                    stream_index, stream_seed = self.aovs.count[x, y], seed ^ FEATURE_SEED_SALT
                                work += self._camera_sample(x, y, window_x, window_y, full_width, full_height, pixel,
                                                            stream_index, stream_seed, k > 0, max_depth, origin,
                                                            forward, right, up, half_height, aperture, focus)
                        else:
                            work += self._camera_sample(x, y, window_x, window_y, full_width, full_height, pixel, index,
                                                        seed, False, max_depth, origin, forward, right, up,
                                                        half_height, aperture, focus)
                    # One plain store per pixel: += on a global field would be an atomic add per sample.
                    self.work[x, y] = self.work[x, y] + work

    @ti.func
    def _camera_sample(self, x, y, window_x, window_y, full_width, full_height, pixel, index, stream_seed,
                       features_only, max_depth, origin, forward, right, up, half_height, aperture, focus):
        """One camera sample of the film's pixel (x, y), the image's (x + window_x, y + window_y),
        at sampler `index` under `stream_seed`: added to the film unless `features_only`, and to the
        AOVs where they are kept; returns its work stats. The kernel's only call of the integrator:
        another call site would compile its tracing in again."""
        state = self.sampler.start(pixel, index, stream_seed)
        # The ray and the filter's image edges are the whole image's, so a crop window's pixels
        # are the same as in the whole render.
        ix, iy = x + window_x, y + window_y
        jitter, weight = pixel_sample(self.sampler.get2d(state, dims.PIXEL), ix, iy, full_width, full_height,
                                      self.features.pixel_filter)
        ray = generate_ray(ix, iy, full_width, full_height, jitter, self.sampler, state, origin, forward, right, up,
                           half_height, aperture, focus, self.features.depth_of_field,
                           self.features.orthographic)
        if ti.static(self.filters_textures):  # the pixel's footprint narrows as its samples accumulate
            shrink = footprint_shrink(index)
            ray.cone_width *= shrink
            ray.cone_spread *= shrink
        value, stats, albedo, normal = self._trace(ray, state, max_depth, features_only)
        if ti.static(self.features.pixel_filter[0] != "box"):
            value *= weight
        if not features_only:
            self.film.add_sample(x, y, value)
        if ti.static(self.writes_aovs):
            self.aovs.add(x, y, albedo, normal)
        return stats

    @ti.func
    def _trace(self, ray, state, max_depth, features_only):
        """The integrator's li, with its features_only flag where it has one (integrators with AOVs)."""
        if ti.static(self.feature_tracing):
            return self.integrator.li(self, ray, state, max_depth, features_only)
        else:
            return self.integrator.li(self, ray, state, max_depth)

    @ti.func
    def _camera_ray(self, u, v, width, height, origin, forward, right, up, half_height):
        """The camera ray through (u, v) in [0,1]^2 of a width x height image (y up), without a
        cone: the SDF march stops within its finest threshold of the surface (a pixel's cone stops
        it some % short at a grazing floor)."""
        o, d = pinhole_ray(2.0 * u - 1.0, 2.0 * v - 1.0, width / height, origin, forward, right, up, half_height,
                           self.features.orthographic)
        return Ray(o=o, d=d, cone_width=0.0, cone_spread=0.0)

    @ti.kernel
    def hit_primitives(self, full_width: ti.i32, full_height: ti.i32, window_x: ti.i32, window_y: ti.i32,
                       origin: ti.math.vec3, forward: ti.math.vec3, right: ti.math.vec3, up: ti.math.vec3,
                       half_height: ti.f32, out: ti.types.ndarray(dtype=ti.i32, ndim=2)):
        """The primitive the ray through each film pixel's centre meets first (-1: none), out[x, y]
        with y up, the film lying on the image as its window says (picking's highlight)."""
        for x, y in ti.ndrange(out.shape[0], out.shape[1]):
            ray = self._camera_ray((x + window_x + 0.5) / full_width, (y + window_y + 0.5) / full_height,
                                   full_width, full_height, origin, forward, right, up, half_height)
            hit = self.geometry.intersect(ray, INF)
            out[x, y] = hit.prim if hit.hit == 1 else -1

    @ti.kernel
    def pick(self, u: ti.f32, v: ti.f32, width: ti.i32, height: ti.i32, origin: ti.math.vec3,
             forward: ti.math.vec3, right: ti.math.vec3, up: ti.math.vec3, half_height: ti.f32,
             floats: ti.template(), ints: ti.template()):
        """What the camera ray through (u, v) in [0,1]^2 (y up) meets: ints = (hit, material, prim,
        instance, front face), floats = (distance along the ray, point, shading normal, uv, distance
        along `forward`: the lens's focus)."""
        for _ in range(1):  # a parallel loop of one: the march's `break` may not sit in the outermost scope
            ray = self._camera_ray(u, v, width, height, origin, forward, right, up, half_height)
            hit = self.geometry.intersect(ray, INF)
            ints[0] = hit.hit
            if hit.hit == 1:
                s = self.geometry.surface(ray, hit)
                ints[1], ints[2], ints[3], ints[4] = s.material, s.prim, hit.instance, s.front_face
                floats[0] = hit.t
                for k in ti.static(range(3)):
                    floats[1 + k] = s.p[k]
                    floats[4 + k] = s.n_shading[k]
                floats[7], floats[8] = s.uv[0], s.uv[1]
                floats[9] = hit.t * ray.d.dot(forward)

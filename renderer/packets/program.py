"""A rendering program whose kernel traces packets of rays: `width` neighbouring pixels of a pass
per loop index, one path a lane (renderer/packets/path.py), on the CPU.

It renders what RenderProgram renders for the scenes renderer/packets/support.py admits, with the
same launch arguments, pixel slices, adaptive stops, crop windows and sample indices (each lane's
pixel continues at its own count), the same sampler numbers per decision and the same film
updates; picking and the picked objects' highlight go to the scalar program (`scalar`), made on
first use. The lanes are a pass's consecutive loop indices: in a whole round, a row's neighbouring
pixels, whose camera rays stay together through the first hit.
"""
import taichi as ti

from renderer.camera import pinhole_ray, pixel_footprint
from renderer.film.adaptive import STOPPED
from renderer.film.band_table import pass_layout, pass_pixel
from renderer.film.pixel_filter import pixel_sample
from renderer.film.pixel_slices import BANDS, ROUND_SLICES
from renderer.geometry.texture_footprint import footprint_shrink
from renderer.materials.bsdf import Bsdf
from renderer.packets.path import trace_paths, uniform2
from renderer.packets.support import SURFACE_FEATURES, scalar_bounces
from renderer.sampling import dims
from renderer.sampling.rng import sample_key


@ti.data_oriented
class PacketProgram:
    sliced = True  # its passes are pixel slices, as RenderProgram's
    feature_samples = False

    def __init__(self, geometry, records, materials, environment, integrator, film, work, features, lights, bands,
                 width, make_scalar, aovs=None):
        """records: PrimitiveRecords; lights: PacketLights; width: rays a packet (8: AVX2's lanes; 16: AVX-512's);
        make_scalar: builds the scalar RenderProgram of the same combination (picking); aovs: the
        denoiser's AovFilm, written as RenderProgram writes it (no feature samples), or None."""
        self.geometry = geometry
        self.records = records
        self.materials = materials
        self.environment = environment
        self.integrator = integrator
        self.film = film
        self.work = work
        self.features = features
        self.lights = lights
        self.bands = bands
        self.width = width
        self.aovs = aovs
        self.writes_aovs = aovs is not None
        # Every lane takes the geometry's own surface record and the scalar BSDF where what the
        # surface point looks like varies over a primitive or needs more than its kind, base colour and
        # shading normal (textures, maps, vertex colours, mixes, anisotropic frames, one-sided faces)
        self.surface_records = any(getattr(features, name) for name in SURFACE_FEATURES)
        # Vertex normals, interpolated in lanes (renderer/packets/shading_normals.py) where the
        # records are not taken
        self.shading_normals = geometry.has_normals
        # The scalar BSDF, for those lanes and the lanes on materials other than Lambert's
        # (renderer/packets/path.py); None where neither is found, which then compile none of it
        self.has_general = bool(set(features.material_kinds) - {"diffuse"}) or self.surface_records
        # Rays carry cones (the pixel's footprint) where textures are filtered, as RenderProgram's
        self.filters_textures = getattr(geometry, "filters_textures", False)
        self.bsdf = Bsdf(materials, features) if self.has_general else None
        # Rough conductors as lanes (renderer/packets/conductor.py) where their lobe is isotropic GGX
        self.lane_conductors = ("conductor" in features.material_kinds and not self.surface_records
                                and not features.has_microfacet_models)
        self.scalar_bounces = scalar_bounces(geometry)  # a large world's incoherent rays: one lane at a time
        self._make_scalar = make_scalar
        self._scalar = None
        # Lane occupancy, summed over launches: (closest-hit traces, their live lanes, shadow
        # traces, their live lanes); occupancy() reads it, reset_occupancy() clears it
        self.traces = ti.field(ti.i64, shape=4)
        # Written, never read: what keeps lanes.seeded's stores (one plain store a packet)
        self._seeds = ti.field(ti.f32, shape=())

    def occupancy(self) -> dict:
        """The share of a packet's lanes that carried a live ray, per kind of trace, since the last
        reset_occupancy() (None where no trace of that kind ran)."""
        calls, closest_lanes, shadow_calls, shadow_lanes = (int(v) for v in self.traces.to_numpy())
        return {"closest": closest_lanes / (calls * self.width) if calls else None,
                "shadow": shadow_lanes / (shadow_calls * self.width) if shadow_calls else None,
                "closest_traces": calls, "shadow_traces": shadow_calls}

    def reset_occupancy(self) -> None:
        self.traces.fill(0)

    def scalar(self):
        if self._scalar is None:
            self._scalar = self._make_scalar()
        return self._scalar

    def pick(self, *args):
        self.scalar().pick(*args)

    def hit_primitives(self, *args):
        self.scalar().hit_primitives(*args)

    def render(self, width: int, height: int, spp: int, slice_first: int, slice_count: int, order: int,
               *rest, feature_boost: int = 0, window=None) -> None:
        """RenderProgram.render's contract (no feature samples: those scenes render one ray at a time)."""
        if feature_boost > 0:
            raise ValueError("feature samples asked of a packet program (it has none)")
        if order == BANDS and slice_count < ROUND_SLICES:
            self.bands.set_height(height)
        window_args = window.kernel_args if window is not None else (width, height, 0, 0)
        self._render(width, height, spp, slice_first, slice_count, order, *rest, *window_args)

    @ti.kernel
    def _render(self, width: ti.i32, height: ti.i32, spp: ti.i32, slice_first: ti.i32, slice_count: ti.i32,
                order: ti.i32, seed: ti.u32, max_depth: ti.i32, origin: ti.math.vec3, forward: ti.math.vec3,
                right: ti.math.vec3, up: ti.math.vec3, half_height: ti.f32, aperture: ti.f32, focus: ti.f32,
                full_width: ti.i32, full_height: ti.i32, window_x: ti.i32, window_y: ti.i32):
        lanes = ti.static(self.width)
        banded, layout, n = pass_layout(self.bands, slice_first, slice_count, width, height, order)
        for packet in range((n + lanes - 1) // lanes):
            xs = ti.Vector([0] * lanes, dt=ti.i32)
            ys = ti.Vector([0] * lanes, dt=ti.i32)
            valid = ti.Vector([0] * lanes, dt=ti.i32)
            first = ti.Vector([0] * lanes, dt=ti.i32)
            pixel = ti.Vector([0] * lanes, dt=ti.u32)
            for k in range(lanes):
                i = packet * lanes + k
                if i < n:
                    x, y = pass_pixel(self.bands, i, banded, slice_first, slice_count, width, height, order, layout)
                    if x < width and y < height:
                        if self.film.adaptive[x, y] != STOPPED:
                            xs[k], ys[k], valid[k] = x, y, 1
                            first[k] = self.film.count[x, y] + self.film.rejected[x, y]
                            pixel[k] = ti.cast((y + window_y) * full_width + x + window_x, ti.u32)
            if valid.max() > 0:
                work_v = ti.Vector([0.0] * lanes, dt=ti.f32)
                work_t = ti.Vector([0.0] * lanes, dt=ti.f32)
                work_r = ti.Vector([0.0] * lanes, dt=ti.f32)
                traces = ti.math.ivec4(0)
                aspect = full_width / full_height
                footprint = pixel_footprint(half_height, full_height)  # a pixel's, before its samples narrow it
                for s in range(spp):
                    # Each lane's key alone: sample_key on lanes whose values were set under
                    # branches trips an assertion of Taichi 1.7.4's store-to-load forwarding.
                    key = ti.Vector([0] * lanes, dt=ti.u32)
                    for k in range(lanes):
                        key[k] = sample_key(pixel[k], first[k] + s, seed)
                    jx, jy = uniform2(key, dims.PIXEL)
                    # Where in its pixel each lane's ray goes, drawn from the pixel filter as RenderProgram draws
                    # it (the box's: the numbers themselves), and the sample's weight
                    weight = jx * 0.0 + 1.0
                    if ti.static(self.features.pixel_filter[0] != "box"):
                        for k in range(lanes):
                            position, w = pixel_sample(ti.math.vec2(jx[k], jy[k]), xs[k] + window_x, ys[k] + window_y,
                                                       full_width, full_height, self.features.pixel_filter)
                            jx[k], jy[k], weight[k] = position.x, position.y, w
                    ox, oy, oz = jx * 0.0, jx * 0.0, jx * 0.0
                    dx, dy, dz = jx * 0.0, jx * 0.0, jx * 0.0
                    # The cone's spread (RenderProgram's: a pixel's angle, narrowing as its samples accumulate)
                    spread = jx * 0.0
                    if ti.static(self.filters_textures):
                        for k in range(lanes):
                            spread[k] = footprint * footprint_shrink(first[k] + s)
                    u = 2.0 * (ti.cast(xs + window_x, ti.f32) + jx) / full_width - 1.0
                    v = 2.0 * (ti.cast(ys + window_y, ti.f32) + jy) / full_height - 1.0
                    for k in range(lanes):
                        o, d = pinhole_ray(u[k], v[k], aspect, origin, forward, right, up, half_height,
                                           self.features.orthographic)
                        ox[k], oy[k], oz[k] = o.x, o.y, o.z
                        dx[k], dy[k], dz[k] = d.x, d.y, d.z
                    r, g, b, visits, tests, rays, occupancy, seeds, aov = trace_paths(self, key, ox, oy, oz, dx, dy,
                                                                                      dz, spread, valid, max_depth)
                    traces += occupancy
                    self._seeds[None] = seeds
                    work_v += visits
                    work_t += tests
                    work_r += rays
                    for k in range(lanes):
                        if valid[k] == 1:
                            self.film.add_sample(xs[k], ys[k], ti.math.vec3(r[k], g[k], b[k]) * weight[k])
                            if ti.static(self.writes_aovs):
                                self.aovs.add(xs[k], ys[k], ti.math.vec3(aov[0][k], aov[1][k], aov[2][k]),
                                              ti.math.vec3(aov[3][k], aov[4][k], aov[5][k]))
                for j in ti.static(range(4)):
                    self.traces[j] += ti.cast(traces[j], ti.i64)  # one atomic add a packet
                for k in range(lanes):
                    if valid[k] == 1:
                        self.work[xs[k], ys[k]] = (self.work[xs[k], ys[k]]
                                                   + ti.math.vec3(work_v[k], work_t[k], work_r[k]))

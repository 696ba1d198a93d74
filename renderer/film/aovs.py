"""Denoising AOVs: the albedo and shading normal a path sees first, accumulated like the colour.

A denoiser (Intel Open Image Denoise) separates noise from detail far better when it is told
what the surfaces are. The tracer reports, for every camera sample, the albedo and shading normal
at its first non-delta vertex: through a mirror or glass the surface seen in it, its albedo
scaled by what the delta bounces passed on (so a red mirror tints what it shows), the normal of
that surface; a path that leaves the scene has the environment's colour clamped to [0, 1] as its
albedo and a zero normal (OIDN's "no surface"). Each pixel keeps the running mean of both and
how many samples it holds, updated in the pixel's own sample order, so they are as reproducible
as the image.

Feature samples. The AOVs of 8 samples are a noisy guide where a pixel covers sub-pixel detail
of a texture (thin lines, a normal map's bevels), and the denoiser then smears or keeps noise.
So in scenes with texture or normal maps, each of a pixel's first FEATURE_BOOSTED_SAMPLES colour
samples brings DEFAULT_FEATURE_BOOST more camera samples that only find the AOVs (the tracer's
`features_only` paths end at the first non-delta vertex): at 8 spp the AOVs hold 40 samples.
The colour is not touched: an image renders bit for bit the same with any boost. Elsewhere an
albedo is constant over a surface, the AOVs' only sub-pixel detail is at edges, and the samples
buy too little for their time. `bench denoise` at 960x540 (relMSE of denoised 8 spp, without ->
with 4 feature samples; render seconds of the 8 spp): textured 0.00172 -> 0.00131 (raw at 128
spp: 0.00146), 1.61 -> 3.09 s; cornell_box 4.63e-4 -> 4.50e-4, 0.92 -> 1.51 s; studio 0.00175 ->
0.00166, 1.06 -> 2.01 s; bunnies 0.00596 -> 0.00526, 1.43 -> 2.91 s; showcase 0.00440 ->
0.00428, 10.4 -> 29.4 s (an SDF camera ray is most of its sample's cost).

Allocated only when asked for (the viewer, `render --denoise` / `--aovs`): 28 bytes a pixel.
"""
import numpy as np
import taichi as ti

from renderer.film.accumulation import is_finite_vec3
from renderer.film.pixel_fields import pixel_scalar, pixel_vector

vec3 = ti.math.vec3

# A pixel's first colour samples that bring feature samples, and how many each brings by default.
FEATURE_BOOSTED_SAMPLES = 8
DEFAULT_FEATURE_BOOST = 4
# Feature samples draw their numbers under the colour seed xor this salt, at the pixel's AOV
# sample count as index: streams of their own, never a colour sample's.
FEATURE_SEED_SALT = 0x5EA7F00D


def scene_feature_boost(features) -> int:
    """The feature samples each early colour sample brings in a scene with these Features: only
    where texture or normal maps put sub-pixel detail into the AOVs (see above)."""
    return DEFAULT_FEATURE_BOOST if features.has_textures or features.has_normal_maps else 0


@ti.func
def clamp_albedo(value):
    """An albedo as the denoiser wants it: in [0, 1] (a spectral or roulette-scaled throughput
    can exceed 1), and 0 where anything upstream went non-finite."""
    out = vec3(0.0)
    if is_finite_vec3(value):
        out = ti.math.clamp(value, 0.0, 1.0)
    return out


@ti.data_oriented
class AovFilm:
    """Per-pixel running means of the first non-delta vertex's albedo and shading normal, and
    the number of samples (colour and feature samples alike) each holds."""

    def __init__(self, max_width: int, max_height: int):
        shape = (max_width, max_height)
        self.albedo = pixel_vector(3, ti.f32, shape)
        self.normal = pixel_vector(3, ti.f32, shape)
        self.count = pixel_scalar(ti.i32, shape)
        self.width = max_width
        self.height = max_height

    def reset(self, width: int, height: int) -> None:
        self.width = width
        self.height = height
        self._clear()

    @ti.kernel
    def _clear(self):
        for x, y in self.albedo:
            self.albedo[x, y] = vec3(0.0)
            self.normal[x, y] = vec3(0.0)
            self.count[x, y] = 0

    @ti.func
    def add(self, x: ti.i32, y: ti.i32, albedo, normal):
        """One more sample of pixel (x, y). Non-finite values count as zero: they must never
        reach the denoiser."""
        a = clamp_albedo(albedo)
        n = vec3(0.0)
        if is_finite_vec3(normal):
            n = ti.math.clamp(normal, -1.0, 1.0)
        count = self.count[x, y] + 1
        weight = 1.0 / ti.cast(count, ti.f32)
        self.albedo[x, y] = self.albedo[x, y] + (a - self.albedo[x, y]) * weight
        self.normal[x, y] = self.normal[x, y] + (n - self.normal[x, y]) * weight
        self.count[x, y] = count

    # --- downloads and restores of the active region (numpy, row 0 = top) ------------------------

    def images(self) -> tuple[np.ndarray, np.ndarray]:
        """(albedo, normal), float32 (height, width, 3) each."""
        albedo, normal, _ = self.state()
        return albedo, normal

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(albedo, normal, count): float32 (height, width, 3) twice and int32 (height, width)."""
        albedo = np.empty((self.height, self.width, 3), dtype=np.float32)
        normal = np.empty((self.height, self.width, 3), dtype=np.float32)
        count = np.empty((self.height, self.width), dtype=np.int32)
        self._transfer(albedo, normal, count, self.width, self.height, False)
        return albedo, normal, count

    def restore(self, albedo: np.ndarray, normal: np.ndarray, count: np.ndarray) -> None:
        height, width = albedo.shape[:2]
        self.reset(width, height)
        self._transfer(np.ascontiguousarray(albedo, dtype=np.float32), np.ascontiguousarray(normal, dtype=np.float32),
                       np.ascontiguousarray(count, dtype=np.int32), width, height, True)

    def write_pixels(self, xs: np.ndarray, ys: np.ndarray, albedo: np.ndarray, normal: np.ndarray,
                     count: np.ndarray) -> None:
        """Set pixels (xs[i], ys[i]) (y up) from (n, 3), (n, 3) and (n,) arrays (Film.write_pixels)."""
        self._pixels(xs, ys, albedo, normal, np.ascontiguousarray(count, dtype=np.int32), True)

    def read_pixels(self, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(albedo, normal, count) of pixels (xs[i], ys[i]): (n, 3), (n, 3) and (n,)."""
        albedo = np.empty((len(xs), 3), np.float32)
        normal = np.empty((len(xs), 3), np.float32)
        count = np.empty(len(xs), np.int32)
        self._pixels(xs, ys, albedo, normal, count, False)
        return albedo, normal, count

    @ti.kernel
    def _pixels(self, xs: ti.types.ndarray(), ys: ti.types.ndarray(), albedo: ti.types.ndarray(),
                normal: ti.types.ndarray(), count: ti.types.ndarray(), write: ti.template()):
        for i in range(xs.shape[0]):
            x, y = xs[i], ys[i]
            if ti.static(write):
                self.count[x, y] = count[i]
            else:
                count[i] = self.count[x, y]
            for c in ti.static(range(3)):
                if ti.static(write):
                    self.albedo[x, y][c] = albedo[i, c]
                    self.normal[x, y][c] = normal[i, c]
                else:
                    albedo[i, c] = self.albedo[x, y][c]
                    normal[i, c] = self.normal[x, y][c]

    @ti.kernel
    def _transfer(self, albedo: ti.types.ndarray(), normal: ti.types.ndarray(), count: ti.types.ndarray(),
                  width: ti.i32, height: ti.i32, upload: ti.template()):
        for y, x in ti.ndrange(height, width):
            row = height - 1 - y
            if ti.static(upload):
                self.count[x, y] = count[row, x]
            else:
                count[row, x] = self.count[x, y]
            for c in ti.static(range(3)):
                if ti.static(upload):
                    self.albedo[x, y][c] = albedo[row, x, c]
                    self.normal[x, y][c] = normal[row, x, c]
                else:
                    albedo[row, x, c] = self.albedo[x, y][c]
                    normal[row, x, c] = self.normal[x, y][c]

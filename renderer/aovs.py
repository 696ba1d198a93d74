"""Denoising AOVs: the albedo and shading normal a path sees first, accumulated like the colour.

A denoiser (Intel Open Image Denoise) separates noise from detail far better when it is told
what the surfaces are. The tracer reports, for every camera sample, the albedo and shading normal
at its first non-delta vertex: through a mirror or glass the surface seen in it, its albedo
scaled by what the delta bounces passed on (so a red mirror tints what it shows), the normal of
that surface; a path that leaves the scene has the environment's colour clamped to [0, 1] as its
albedo and a zero normal (OIDN's "no surface"). Each pixel keeps the running mean of both,
indexed by its own sample index like the film, so they are as reproducible as the image.

Allocated only when asked for (the viewer, `render --denoise` / `--aovs`): 24 bytes a pixel.
"""
import numpy as np
import taichi as ti

from renderer.film import is_finite_vec3
from renderer.pixel_fields import pixel_vector

vec3 = ti.math.vec3


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
    """Per-pixel running means of the first non-delta vertex's albedo and shading normal."""

    def __init__(self, max_width: int, max_height: int):
        shape = (max_width, max_height)
        self.albedo = pixel_vector(3, ti.f32, shape)
        self.normal = pixel_vector(3, ti.f32, shape)
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

    @ti.func
    def add(self, x: ti.i32, y: ti.i32, index: ti.i32, albedo, normal):
        """Sample `index` (0-based, the pixel's own sample index) of pixel (x, y). Non-finite
        values count as zero: they must never reach the denoiser."""
        a = clamp_albedo(albedo)
        n = vec3(0.0)
        if is_finite_vec3(normal):
            n = ti.math.clamp(normal, -1.0, 1.0)
        weight = 1.0 / ti.cast(index + 1, ti.f32)
        self.albedo[x, y] = self.albedo[x, y] + (a - self.albedo[x, y]) * weight
        self.normal[x, y] = self.normal[x, y] + (n - self.normal[x, y]) * weight

    # --- downloads and restores of the active region (numpy, row 0 = top) ------------------------

    def images(self) -> tuple[np.ndarray, np.ndarray]:
        """(albedo, normal), float32 (height, width, 3) each."""
        albedo = np.empty((self.height, self.width, 3), dtype=np.float32)
        normal = np.empty((self.height, self.width, 3), dtype=np.float32)
        self._download(albedo, normal, self.width, self.height)
        return albedo, normal

    def restore(self, albedo: np.ndarray, normal: np.ndarray) -> None:
        height, width = albedo.shape[:2]
        self.reset(width, height)
        self._upload(np.ascontiguousarray(albedo, dtype=np.float32), np.ascontiguousarray(normal, dtype=np.float32),
                     width, height)

    def write_pixels(self, xs: np.ndarray, ys: np.ndarray, albedo: np.ndarray, normal: np.ndarray) -> None:
        """Set the running means of pixels (xs[i], ys[i]) (y up) from (n, 3) arrays (Film.write_pixels)."""
        self._pixels(xs, ys, albedo, normal, True)

    def read_pixels(self, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(albedo, normal) of pixels (xs[i], ys[i]), (n, 3) each."""
        albedo = np.empty((len(xs), 3), np.float32)
        normal = np.empty((len(xs), 3), np.float32)
        self._pixels(xs, ys, albedo, normal, False)
        return albedo, normal

    @ti.kernel
    def _pixels(self, xs: ti.types.ndarray(), ys: ti.types.ndarray(), albedo: ti.types.ndarray(),
                normal: ti.types.ndarray(), write: ti.template()):
        for i in range(xs.shape[0]):
            x, y = xs[i], ys[i]
            for c in ti.static(range(3)):
                if ti.static(write):
                    self.albedo[x, y][c] = albedo[i, c]
                    self.normal[x, y][c] = normal[i, c]
                else:
                    albedo[i, c] = self.albedo[x, y][c]
                    normal[i, c] = self.normal[x, y][c]

    @ti.kernel
    def _download(self, albedo: ti.types.ndarray(), normal: ti.types.ndarray(), width: ti.i32, height: ti.i32):
        for y, x in ti.ndrange(height, width):
            for c in ti.static(range(3)):
                albedo[height - 1 - y, x, c] = self.albedo[x, y][c]
                normal[height - 1 - y, x, c] = self.normal[x, y][c]

    @ti.kernel
    def _upload(self, albedo: ti.types.ndarray(), normal: ti.types.ndarray(), width: ti.i32, height: ti.i32):
        for y, x in ti.ndrange(height, width):
            for c in ti.static(range(3)):
                self.albedo[x, y][c] = albedo[height - 1 - y, x, c]
                self.normal[x, y][c] = normal[height - 1 - y, x, c]

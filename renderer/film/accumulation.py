"""Progressive accumulation of radiance samples on the device.

Each pixel keeps a running mean and Welford's sum of squared deviations (m2) instead of a plain
sum: the mean of a constant stays exactly that constant after any number of samples, and the
variance needs no catastrophic `sum(x^2) - n * mean^2` subtraction in f32.

Fields are indexed [x, y] with y pointing up. Only the active region [0:width, 0:height] is used,
so a viewer can render at a lower internal resolution into the same (max-size) film.
"""

import math
from dataclasses import dataclass

import numpy as np
import taichi as ti

from renderer.spectral.luminance import luminance
from renderer.film.pixel_fields import pixel_scalar, pixel_vector

NOISE_LUMINANCE_FLOOR = 1e-3  # relative error of near-black pixels would blow up without it


@ti.func
def is_finite_f32(value):
    # Tests on the bit pattern: with fast math (Taichi's default) `v != v` is folded to False.
    # An all-ones exponent means +-inf or NaN.
    bits = ti.bit_cast(value, ti.i32)
    return (bits & 0x7F800000) != 0x7F800000


@ti.func
def is_finite_vec3(value):
    return is_finite_f32(value[0]) and is_finite_f32(value[1]) and is_finite_f32(value[2])


@dataclass
class FilmState:
    """A film's accumulation of its active region, bit for bit (numpy, row 0 = top).

    Restoring it and adding samples gives the same float32 values as never having stopped: the
    Welford update of a pixel depends only on its own (mean, m2, count) and the new sample.
    """

    mean: np.ndarray  # float32 (height, width, 3)
    m2: np.ndarray  # float32 (height, width, 3): Welford's sum of squared deviations
    count: np.ndarray  # int32 (height, width): accepted samples
    rejected: np.ndarray  # int32 (height, width): non-finite samples dropped
    # Optional layers (None: absent): adaptive sampling's per-pixel state (renderer/film/adaptive.py) and
    # the denoising AOVs' running means (renderer/film/aovs.py).
    adaptive: np.ndarray | None = None  # int32 (height, width)
    albedo: np.ndarray | None = None  # float32 (height, width, 3)
    normal: np.ndarray | None = None  # float32 (height, width, 3)
    aov_count: np.ndarray | None = None  # int32 (height, width): the AOVs' samples, feature samples included

    ARRAYS = (("mean", np.float32, 3), ("m2", np.float32, 3), ("count", np.int32, 0), ("rejected", np.int32, 0))
    OPTIONAL_ARRAYS = (("adaptive", np.int32, 0), ("albedo", np.float32, 3), ("normal", np.float32, 3),
                       ("aov_count", np.int32, 0))

    def aov_samples(self) -> np.ndarray:
        """The AOVs' sample counts: those kept, or for a state saved before feature samples
        existed (one AOV sample per colour sample, rejected ones included), count + rejected."""
        if self.aov_count is not None:
            return self.aov_count
        return self.count + self.rejected

    @property
    def size(self) -> tuple[int, int]:
        height, width = self.count.shape
        return width, height

    def problem(self) -> str | None:
        """What is wrong with the arrays' types or shapes (None: a valid state)."""
        if np.ndim(self.count) != 2:
            return f"sample counts have shape {np.shape(self.count)}, expected (height, width)"
        height, width = self.count.shape
        for name, dtype, channels in self.ARRAYS + self.OPTIONAL_ARRAYS:
            array = getattr(self, name)
            if array is None and (name, dtype, channels) in self.OPTIONAL_ARRAYS:
                continue
            shape = (height, width, channels) if channels else (height, width)
            if not isinstance(array, np.ndarray) or array.dtype != dtype or array.shape != shape:
                return (f"'{name}' is {getattr(array, 'dtype', type(array).__name__)} {np.shape(array)}, "
                        f"expected {np.dtype(dtype)} {shape}")
        return None


@ti.data_oriented
class Film:
    def __init__(self, max_width: int, max_height: int):
        if max_width < 1 or max_height < 1:
            raise ValueError(f"film size must be positive, got {max_width}x{max_height}")
        self.max_width = max_width
        self.max_height = max_height
        shape = (max_width, max_height)
        self.mean = pixel_vector(3, ti.f32, shape)
        self.m2 = pixel_vector(3, ti.f32, shape)
        self.count = pixel_scalar(ti.i32, shape)
        self.rejected = pixel_scalar(ti.i32, shape)
        self.adaptive = pixel_scalar(ti.i32, shape)  # adaptive sampling's state (renderer/film/adaptive.py)
        # stats()' partial reductions, one entry per film row (summed on the host): [min spp,
        # rejected, pixels with a noise estimate], [spp sum, sum of squared relative errors].
        self._row_ints = ti.field(ti.i32, shape=(max_height, 3))
        self._row_floats = ti.field(ti.f32, shape=(max_height, 2))
        self.width = max_width
        self.height = max_height

    def reset(self, width: int, height: int) -> None:
        """Clear all accumulated samples and make [0:width, 0:height] the active region."""
        if not (1 <= width <= self.max_width and 1 <= height <= self.max_height):
            raise ValueError(
                f"active size {width}x{height} outside 1x1..{self.max_width}x{self.max_height}"
            )
        self.width = width
        self.height = height
        self._clear()

    @ti.kernel
    def _clear(self):
        # One kernel for the five fields (five fill() calls would compile five).
        for x, y in self.mean:
            self.mean[x, y] = ti.math.vec3(0.0)
            self.m2[x, y] = ti.math.vec3(0.0)
            self.count[x, y] = 0
            self.rejected[x, y] = 0
            self.adaptive[x, y] = 0

    def state(self) -> FilmState:
        """The exact accumulation of the active region (what a checkpoint keeps)."""
        m2 = np.empty((self.height, self.width, 3), dtype=np.float32)
        self._copy_vec3(self.m2, m2, self.width, self.height)
        return FilmState(self.mean_image(), m2, self.sample_counts(), self.rejected_counts(),
                         adaptive=self._active_rows(self.adaptive.to_numpy()))

    def restore(self, state: FilmState) -> None:
        """Make `state` the film's accumulation, its size the active region; adding samples then
        continues exactly where the film that produced it stopped."""
        problem = state.problem()
        if problem:
            raise ValueError(f"film state: {problem}")
        self.reset(*state.size)
        adaptive = state.adaptive if state.adaptive is not None else np.zeros_like(state.count)
        self._load_state(state.mean, state.m2, state.count, state.rejected, adaptive, self.width, self.height)

    @ti.kernel
    def _load_state(self, mean: ti.types.ndarray(), m2: ti.types.ndarray(), count: ti.types.ndarray(),
                    rejected: ti.types.ndarray(), adaptive: ti.types.ndarray(), width: ti.i32, height: ti.i32):
        # One kernel for the five fields (from_numpy would compile one per field).
        for y, x in ti.ndrange(height, width):
            row = height - 1 - y
            for c in ti.static(range(3)):
                self.mean[x, y][c] = mean[row, x, c]
                self.m2[x, y][c] = m2[row, x, c]
            self.count[x, y] = count[row, x]
            self.rejected[x, y] = rejected[row, x]
            self.adaptive[x, y] = adaptive[row, x]

    def write_pixels(self, xs: np.ndarray, ys: np.ndarray, arrays: dict[str, np.ndarray]) -> None:
        """Set the accumulation of pixels (xs[i], ys[i]) (film coordinates, y up) from per-pixel
        arrays (renderer/commands/distributed/pixel_groups.py: "mean", "m2" (n, 3), "count", "rejected",
        "adaptive" (n,)); the other pixels keep theirs. A distributed render's worker takes a group
        of pixels' exact state this way, without touching the rest of its film."""
        self._write_pixels(xs, ys, arrays["mean"], arrays["m2"], arrays["count"], arrays["rejected"],
                           arrays["adaptive"])

    def read_pixels(self, xs: np.ndarray, ys: np.ndarray) -> dict[str, np.ndarray]:
        """The accumulation of pixels (xs[i], ys[i]), as write_pixels takes it."""
        n = len(xs)
        arrays = {"mean": np.empty((n, 3), np.float32), "m2": np.empty((n, 3), np.float32),
                  "count": np.empty(n, np.int32), "rejected": np.empty(n, np.int32), "adaptive": np.empty(n, np.int32)}
        self._read_pixels(xs, ys, arrays["mean"], arrays["m2"], arrays["count"], arrays["rejected"], arrays["adaptive"])
        return arrays

    def _write_pixels(self, xs, ys, mean, m2, count, rejected, adaptive):
        self._pixels(xs, ys, mean, m2, count, rejected, adaptive, True)

    def _read_pixels(self, xs, ys, mean, m2, count, rejected, adaptive):
        self._pixels(xs, ys, mean, m2, count, rejected, adaptive, False)

    @ti.kernel
    def _pixels(self, xs: ti.types.ndarray(), ys: ti.types.ndarray(), mean: ti.types.ndarray(),
                m2: ti.types.ndarray(), count: ti.types.ndarray(), rejected: ti.types.ndarray(),
                adaptive: ti.types.ndarray(), write: ti.template()):
        # One kernel body for both directions (`write` is compile-time).
        for i in range(xs.shape[0]):
            x, y = xs[i], ys[i]
            if ti.static(write):
                for c in ti.static(range(3)):
                    self.mean[x, y][c] = mean[i, c]
                    self.m2[x, y][c] = m2[i, c]
                self.count[x, y] = count[i]
                self.rejected[x, y] = rejected[i]
                self.adaptive[x, y] = adaptive[i]
            else:
                for c in ti.static(range(3)):
                    mean[i, c] = self.mean[x, y][c]
                    m2[i, c] = self.m2[x, y][c]
                count[i] = self.count[x, y]
                rejected[i] = self.rejected[x, y]
                adaptive[i] = self.adaptive[x, y]

    @ti.func
    def add_sample(self, x: ti.i32, y: ti.i32, value: ti.math.vec3):
        """Welford update of pixel (x, y); a sample with any NaN/inf component is only counted.

        Not atomic: within one kernel launch, a given pixel must be updated by a single thread.
        """
        if is_finite_vec3(value):
            n = self.count[x, y] + 1
            self.count[x, y] = n
            delta = value - self.mean[x, y]
            new_mean = self.mean[x, y] + delta / ti.cast(n, ti.f32)
            self.mean[x, y] = new_mean
            # An assignment, not +=: on a global field += compiles to an atomic add, and each
            # pixel has one writer here anyway.
            self.m2[x, y] = self.m2[x, y] + delta * (value - new_mean)
        else:
            self.rejected[x, y] += 1

    @ti.func
    def set_estimate(self, x: ti.i32, y: ti.i32, value: ti.math.vec3, passes: ti.i32):
        """Make `value` the pixel's image, for integrators whose image is not a mean of independent
        samples (sppm): mean = value, count = passes, and m2 = +inf, i.e. variance unknown (so
        `variance_of_mean_image` says inf and `stats()` gives no noise estimate, never a false 0).
        A non-finite value keeps the previous estimate and is counted as rejected."""
        if is_finite_vec3(value):
            self.mean[x, y] = value
        else:
            self.rejected[x, y] = self.rejected[x, y] + 1
        self.count[x, y] = passes
        self.m2[x, y] = ti.math.vec3(ti.math.inf)

    # --- downloads of the active region (numpy, row 0 = top) ---------------------------------

    def mean_image(self) -> np.ndarray:
        """Per-pixel mean radiance, float32 (height, width, 3)."""
        out = np.empty((self.height, self.width, 3), dtype=np.float32)
        self._copy_vec3(self.mean, out, self.width, self.height)
        return out

    def variance_of_mean_image(self) -> np.ndarray:
        """Per-channel variance of the pixel mean, s^2 / n, float32 (height, width, 3).

        s^2 is the unbiased sample variance. With fewer than 2 samples it is unknown: +inf.
        """
        out = np.empty((self.height, self.width, 3), dtype=np.float32)
        self._copy_variance_of_mean(out, self.width, self.height)
        return out

    def sample_counts(self) -> np.ndarray:
        """Accepted samples per pixel, int32 (height, width)."""
        return self._active_rows(self.count.to_numpy())

    def rejected_counts(self) -> np.ndarray:
        """Dropped non-finite samples per pixel, int32 (height, width)."""
        return self._active_rows(self.rejected.to_numpy())

    def stats(self) -> dict:
        """Summary of the active region, reduced on the device.

        noise: root mean square over pixels of the relative standard error of the pixel mean in
        luminance, sqrt(var / n) / max(luminance(mean), 1e-3). The luminance standard error is
        taken as luminance(per-channel standard error): an upper bound that is exact when the
        channels are fully correlated (grey). Pixels with < 2 samples have no estimate; if no pixel
        has one, noise is +inf.
        """
        self._reduce_stats(self.width, self.height)
        ints = self._row_ints.to_numpy()[: self.height].astype(np.int64)
        floats = self._row_floats.to_numpy()[: self.height].astype(np.float64)
        min_spp, rejected, noise_pixels = int(ints[:, 0].min()), int(ints[:, 1].sum()), int(ints[:, 2].sum())
        spp_sum, squared_error_sum = (float(v) for v in floats.sum(axis=0))
        noise = math.sqrt(squared_error_sum / noise_pixels) if noise_pixels else math.inf
        return {
            "min_spp": min_spp,
            "mean_spp": spp_sum / (self.width * self.height),
            "rejected": rejected,
            "noise": noise,
        }

    def _active_rows(self, full: np.ndarray) -> np.ndarray:
        # [x, y] y-up  ->  [row, column] row 0 = top
        return np.ascontiguousarray(full[: self.width, : self.height].T[::-1])

    @ti.kernel
    def _copy_vec3(self, source: ti.template(), out: ti.types.ndarray(), width: ti.i32, height: ti.i32):
        for y, x in ti.ndrange(height, width):
            for c in ti.static(range(3)):
                out[height - 1 - y, x, c] = source[x, y][c]

    @ti.kernel
    def _copy_variance_of_mean(self, out: ti.types.ndarray(), width: ti.i32, height: ti.i32):
        for y, x in ti.ndrange(height, width):
            variance = self.variance_of_mean_at(x, y)
            for c in ti.static(range(3)):
                out[height - 1 - y, x, c] = variance[c]

    @ti.func
    def variance_of_mean_at(self, x, y):
        """The variance of pixel (x, y)'s mean, per channel (inf with fewer than two samples)."""
        n = self.count[x, y]
        result = ti.math.vec3(ti.math.inf)
        if n >= 2:
            nf = ti.cast(n, ti.f32)
            result = self.m2[x, y] / ((nf - 1.0) * nf)
        return result

    @ti.kernel
    def _reduce_stats(self, width: ti.i32, height: ti.i32):
        # One loop index per row (its pixels adjacent in memory), summed serially: no atomics on
        # shared totals. With them (five global accumulators per pixel, two threads) this took
        # 15-95 ms at 960x540 on a 2-core CPU, the HUD's refresh then making still frames 2-3 times
        # their budget.
        for y in range(height):
            least = 2147483647
            rejected = 0
            noise_pixels = 0
            spp_sum = 0.0
            squared_errors = 0.0
            for x in range(width):
                n = self.count[x, y]
                least = ti.min(least, n)
                rejected += self.rejected[x, y]
                spp_sum += ti.cast(n, ti.f32)
                if n >= 2:
                    standard_error = ti.sqrt(ti.max(self.variance_of_mean_at(x, y), 0.0))
                    relative = luminance(standard_error) / ti.max(luminance(self.mean[x, y]), NOISE_LUMINANCE_FLOOR)
                    squared_errors += relative * relative
                    noise_pixels += 1
            self._row_ints[y, 0] = least
            self._row_ints[y, 1] = rejected
            self._row_ints[y, 2] = noise_pixels
            self._row_floats[y, 0] = spp_sum
            self._row_floats[y, 1] = squared_errors

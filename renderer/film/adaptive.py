"""Adaptive sampling: pixels whose estimate is already precise stop taking samples.

The film keeps Welford's variance per pixel, so each pixel knows the standard error of its mean;
the rule measures it relative to the pixel's level, e = luminance(sqrt(s^2 / n)) /
sqrt(luminance(mean)^2 + 0.1^2): relative where the pixel is brighter than 0.1, absolute below,
the weighting of the relMSE (0.01 added to the squared reference) every benchmark reports. (A
floor of 1e-3, as the HUD's noise figure has, kept dark pixels sampling long after their error
stopped mattering: the Cornell box at 320x180, threshold 0.02, adaptive against uniform at the
time uniform takes for 256 spp, paired z +9.8 (worse) with that floor and -7.8 (better) with
this one, in one run each.) The stopping rule, applied at checks after min_spp, 2 min_spp,
4 min_spp ... samples per pixel (whole rounds):

- a pixel's error at a check is the largest e over its 3x3 neighbourhood, so a pixel next to a
  noisy one keeps sampling (an isolated pixel whose few samples happened to agree is not trusted
  alone; converged regions grow inwards from smooth areas);
- a pixel stops once that error is below the threshold at two consecutive checks (n and 2n
  samples): an estimate of the variance from n samples can be low by chance (a dark pixel that
  has not yet met the rare bright path), and must be confirmed by twice the samples;
- pixels with fewer than min_spp accepted samples never stop.

Stopped pixels keep their samples and are skipped by the render kernel; the film's `adaptive`
field records the state (SAMPLING, ONCE_BELOW, STOPPED), which checkpoints keep, so a resumed
adaptive render continues exactly. `--spp` stays the maximum.
"""
import taichi as ti

from renderer.spectral.luminance import luminance
from renderer.film.pixel_fields import pixel_scalar

SAMPLING = 0
ONCE_BELOW = 1  # below the threshold at the last check: stops if it is again at the next
STOPPED = 2

DEFAULT_MIN_SPP = 16
# The luminance below which a pixel's error counts as absolute rather than relative: the same
# 0.1 (0.01 added to the squared reference) as the relMSE every benchmark reports.
ERROR_FLOOR = 0.1


def check_points(min_spp: int):
    """The samples per pixel after which the stopping rule is applied: min_spp * 2^k."""
    n = max(1, min_spp)
    while True:
        yield n
        n *= 2


def next_check(samples_done: int, min_spp: int) -> int:
    """The first check point strictly after `samples_done`."""
    for n in check_points(min_spp):
        if n > samples_done:
            return n
    raise AssertionError("unreachable")


def is_check_point(samples: int, min_spp: int) -> bool:
    n = max(1, min_spp)
    return samples >= n and samples % n == 0 and ((samples // n) & (samples // n - 1)) == 0


@ti.data_oriented
class AdaptiveSampling:
    """The stopping rule's kernels over a film (its `adaptive` field is the state)."""

    def __init__(self, film):
        self.film = film
        self.error = pixel_scalar(ti.f32, (film.max_width, film.max_height))
        self.active = ti.field(ti.i32, shape=())

    def check(self, threshold: float, min_spp: int) -> int:
        """Apply the rule to the film's active region; the number of pixels still sampling."""
        self._check(self.film.width, self.film.height, threshold, min_spp)
        return int(self.active[None])

    def count_active(self) -> int:
        self._count(self.film.width, self.film.height)
        return int(self.active[None])

    @ti.func
    def _relative_error(self, x, y):
        film = self.film
        error = ti.math.inf
        if film.count[x, y] >= 2:
            standard_error = ti.sqrt(ti.max(film.variance_of_mean_at(x, y), 0.0))
            level = luminance(film.mean[x, y])
            error = luminance(standard_error) / ti.sqrt(level * level + ERROR_FLOOR * ERROR_FLOOR)
        return error

    @ti.kernel
    def _check(self, width: ti.i32, height: ti.i32, threshold: ti.f32, min_spp: ti.i32):
        for y, x in ti.ndrange(height, width):
            self.error[x, y] = self._relative_error(x, y)
        self.active[None] = 0
        for y, x in ti.ndrange(height, width):
            state = self.film.adaptive[x, y]
            if state != STOPPED:
                worst = 0.0
                for dx, dy in ti.static(ti.ndrange((-1, 2), (-1, 2))):
                    nx = ti.min(ti.max(x + dx, 0), width - 1)
                    ny = ti.min(ti.max(y + dy, 0), height - 1)
                    worst = ti.max(worst, self.error[nx, ny])
                below = self.film.count[x, y] >= min_spp and worst < threshold
                if below:
                    state = STOPPED if state == ONCE_BELOW else ONCE_BELOW
                else:
                    state = SAMPLING
                self.film.adaptive[x, y] = state
            if state != STOPPED:
                self.active[None] += 1

    @ti.kernel
    def _count(self, width: ti.i32, height: ti.i32):
        self.active[None] = 0
        for y, x in ti.ndrange(height, width):
            if self.film.adaptive[x, y] != STOPPED:
                self.active[None] += 1

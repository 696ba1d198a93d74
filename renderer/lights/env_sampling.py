"""Importance sampling of the equirectangular environment map.

The distribution is piecewise constant over the map's texels: texel (i, j) (row i from the zenith,
column j in u) is chosen with probability P(i, j) = P(i) P(j | i) and a direction is drawn uniformly
*in solid angle* inside it (uniform in phi and in cos theta), so the pdf is constant per texel:

    pdf(direction) = P(i, j) / Omega_i,   Omega_i = (2 pi / W) (cos theta_i - cos theta_{i+1})

where theta_i are the row edges of the map: halfway between the row centres, which sit at
theta = pi i / (H - 1) as `Environment` looks them up (Mitsuba's convention), so the first and last
rows own half a row each around the poles (`environment.row_edges`). Each cell is then the region
where the bilinear lookup blends its texel with its neighbours, as the bounds below assume.

Why uniform in cos theta within a texel rather than uniform in (u, v) with
pdf = p(u, v) / (2 pi^2 sin theta) and a sin(theta_centre) weight (pbrt-v3's choice): the two agree
as the texels shrink, but this one has a finite pdf everywhere (no 1/sin theta singularity at the
poles, nothing to clamp), weighs each texel by its exact solid angle, and makes radiance/pdf exactly
constant on a constant map, so a white-furnace render under an environment has zero variance from
the light sample.

Texel weights (the distribution is built once, from the image, in the map's own frame; intensity and
rotation are read from `environment.scalars` (and, where compiled in, its full rotation from
`environment.frame`) at run time and change nothing here):

* *Conservative*: the bilinear lookup makes the radiance inside a texel a blend of its 3x3
  neighbourhood, so a texel next to the sun is bright near its shared edge. The weight of a texel is
  the exact maximum luminance the bilinear interpolant reaches inside it (the max over the texel
  centre, its four edge midpoints and its four corners, each an average of 1, 2 or 4 texels; u
  wraps and v clamps as in the lookup). It bounds the radiance from above (so pdf > 0 wherever
  radiance > 0), and it is tighter than the 3x3 maximum: a lone bright texel spreads a quarter of
  its power onto its corners' neighbours and half onto its edge neighbours instead of all of it.
  With that bound, the luminance of radiance / pdf never exceeds sum(weight * Omega): the map's
  total (conservative) power, not its peak. `ratio_bound` is that sup, computed from the stored
  tables.
* *Floor*: every texel gets `FLOOR` (1e-3) times its row's mean weight added in the conditional
  (per-row) distribution, and every row gets `FLOOR` times the mean row weight in the marginal. The
  CDFs are float32, whose resolution near 1 is 2^-24 (6e-8): a texel whose share of its row fell
  below that would have a zero-width CDF interval, so the sampler could never pick it while its
  pdf said otherwise, and MIS with the BSDF sample would lose that light. With the floor every
  texel's share of its row is at least FLOOR / (W (1 + FLOOR)) (2e-6 at W = 512; above 2^-22 up to
  W = 4096), and likewise for rows. It costs at most ~0.2 % of the samples, and a black map (or
  row) becomes uniform instead of 0/0. The stored pdf is computed from the float32 CDFs themselves,
  so the pdf is exactly what the sampler does.

Search: inversion of the marginal and conditional CDFs by binary search (log2(H) + log2(W) steps,
17 for a 512x256 map) rather than alias tables. Inversion is monotone in each sample dimension, so
stratified and low-discrepancy samples stay well distributed over the map (alias tables scramble
them), the second dimension's remainder gives the position inside the texel for free, and the cost
is a handful of cached loads next to a BVH traversal.
"""
import math

import numpy as np
import taichi as ti

from renderer.lights.environment import row_edges
from renderer.spectral.luminance import LUMINANCE_WEIGHTS
from renderer.sampling.cdf import cdf_interval
from renderer.sampling.warps import PI
from renderer.runtime.upload import upload_fields

LUMINANCE = np.array(LUMINANCE_WEIGHTS)
FLOOR = 1e-3  # see the module doc: keeps every float32 CDF interval wider than 2^-22
ONE_MINUS_EPSILON = 0.99999994  # largest float32 below 1: u = 1.0 would index past the last texel


def texel_bounds(image: np.ndarray) -> np.ndarray:
    """(H, W) float64: the maximum luminance of the bilinear interpolant inside each texel.

    Inside a texel's quadrant the lookup is bilinear in the (centre, edge neighbour, other edge
    neighbour, corner neighbour) values with both weights in [1/2, 1], so its maximum is at one of
    the quadrant's corners: the centre value, an edge midpoint (average of 2) or a texel corner
    (average of 4). u wraps and v clamps, as in `Environment._lookup`.
    """
    lum = np.asarray(image, np.float64)[..., :3] @ LUMINANCE
    lum = np.maximum(lum, 0.0)
    up = np.concatenate([lum[:1], lum[:-1]], axis=0)  # clamped in v
    down = np.concatenate([lum[1:], lum[-1:]], axis=0)
    bound = lum.copy()
    for vertical in (up, down):
        np.maximum(bound, 0.5 * (lum + vertical), out=bound)
    for shift in (1, -1):  # wrapped in u
        side = np.roll(lum, shift, axis=1)
        np.maximum(bound, 0.5 * (lum + side), out=bound)
        for vertical in (up, down):
            corner = np.roll(vertical, shift, axis=1)
            np.maximum(bound, 0.25 * (lum + side + vertical + corner), out=bound)
    return bound


def build_distribution(image: np.ndarray, floor: float = FLOOR) -> dict:
    """The sampling tables (numpy) for an (H, W, 3) map: float32 CDFs as the device uses them, and
    float64 views derived from those (probabilities, pdf per texel, the radiance/pdf bound)."""
    height, width = image.shape[:2]
    bound = texel_bounds(image)
    z_edges = np.cos(row_edges(height))
    z_edges[0], z_edges[-1] = 1.0, -1.0
    solid_angle = (2.0 * np.pi / width) * (z_edges[:-1] - z_edges[1:])  # of one texel in row i

    row_mean = bound.mean(axis=1)
    weights = bound + floor * row_mean[:, None]
    weights[row_mean <= 0.0] = 1.0  # a black row: uniform (the marginal floor is all it gets)
    conditional = _cdf(weights)
    rows = solid_angle * bound.sum(axis=1)
    if rows.sum() > 0.0:
        rows = rows + floor * rows.mean()
    else:  # a black map: uniform over the sphere
        rows = solid_angle.copy()
    marginal = _cdf(rows[None, :])[0]

    p_row = np.diff(marginal.astype(np.float64))
    p_col = np.diff(conditional.astype(np.float64), axis=1)
    if not (p_row > 0.0).all() or not (p_col > 0.0).all():
        raise ValueError("environment map too large for float32 CDFs with the current floor")
    probabilities = p_row[:, None] * p_col
    texel_pdf = probabilities / solid_angle[:, None]
    return {
        "bound": bound,
        "marginal_cdf": marginal,
        "conditional_cdf": conditional,
        "probabilities": probabilities,
        "solid_angle": solid_angle,
        "texel_pdf": texel_pdf,
        "north": (1.0 - z_edges),  # 1 - cos theta at the row edges: precise near the zenith
        "south": (1.0 + z_edges),  # 1 + cos theta: precise near the nadir
        # sup over directions of luminance(radiance) / pdf, at intensity 1
        "ratio_bound": float(np.max(bound * solid_angle[:, None] / probabilities)),
    }


def _cdf(weights: np.ndarray) -> np.ndarray:
    """Row-wise CDFs (n, m + 1) in float32, from 0 exactly to 1 exactly."""
    sums = np.cumsum(weights, axis=1)
    cdf = np.zeros((weights.shape[0], weights.shape[1] + 1))
    cdf[:, 1:] = sums / sums[:, -1:]
    cdf[:, -1] = 1.0
    return cdf.astype(np.float32)


@ti.data_oriented
class EnvironmentSampler:
    """Draws directions towards the bright parts of an `Environment` of kind 'map'.

    `sample(u)` and `pdf(direction)` are Taichi funcs; `sample_batch`, `pdf_batch` and
    `radiance_batch` run them over numpy arrays (tests, benchmarks).
    """

    def __init__(self, image: np.ndarray, environment):
        if environment.kind != "map":
            raise ValueError(f"environment sampling needs a map, not kind '{environment.kind}'")
        image = np.asarray(image, np.float32)
        if image.ndim != 3 or image.shape[2] < 3:
            raise ValueError(f"expected an (H, W, 3) image, got {image.shape}")
        if image.shape[:2] != (environment.height, environment.width):
            raise ValueError("the image does not match the environment's texels")
        self.environment = environment
        self.height, self.width = image.shape[:2]
        tables = build_distribution(image)
        self.tables = tables
        self.ratio_bound = tables["ratio_bound"]  # times the intensity, for luminance
        h, w = self.height, self.width
        self.marginal_cdf = ti.field(ti.f32, shape=h + 1)
        self.conditional_cdf = ti.field(ti.f32, shape=(h, w + 1))
        self.texel_pdf = ti.field(ti.f32, shape=(h, w))
        self.north = ti.field(ti.f32, shape=h + 1)
        self.south = ti.field(ti.f32, shape=h + 1)
        upload_fields([(self.marginal_cdf, tables["marginal_cdf"]), (self.conditional_cdf, tables["conditional_cdf"]),
                       (self.texel_pdf, tables["texel_pdf"]), (self.north, tables["north"]),
                       (self.south, tables["south"])])

    @classmethod
    def from_environment(cls, environment):
        """Build from the map already uploaded to the environment's texels."""
        return cls(environment.texels.to_numpy(), environment)

    # -- device side ---------------------------------------------------------------------------

    @ti.func
    def sample(self, u):
        """u: vec2 in [0, 1)^2 -> (direction vec3 (unit), pdf f32 (solid angle), radiance vec3).

        radiance = environment.radiance(direction) (bilinear lookup times intensity)."""
        ux = ti.math.clamp(u.x, 0.0, ONE_MINUS_EPSILON)
        uy = ti.math.clamp(u.y, 0.0, ONE_MINUS_EPSILON)
        # row: largest i with marginal_cdf[i] <= ux (zero-width rows cannot be chosen)
        i = cdf_interval(self.marginal_cdf, 0, self.height, ux)
        c0 = self.marginal_cdf[i]
        fv = ti.math.clamp((ux - c0) / (self.marginal_cdf[i + 1] - c0), 0.0, 1.0)
        j = cdf_interval(self.conditional_cdf, i, self.width, uy)
        c0 = self.conditional_cdf[i, j]
        fu = ti.math.clamp((uy - c0) / (self.conditional_cdf[i, j + 1] - c0), 0.0, 1.0)

        # uniform in cos theta inside the row; 1 -/+ cos theta interpolated where it is small
        z = 0.0
        sin_theta = 0.0
        if 2 * i < self.height:
            t = ti.math.mix(self.north[i], self.north[i + 1], fv)
            z = 1.0 - t
            sin_theta = ti.sqrt(ti.max(0.0, t * (2.0 - t)))
        else:
            s = ti.math.mix(self.south[i], self.south[i + 1], fv)
            z = s - 1.0
            sin_theta = ti.sqrt(ti.max(0.0, s * (2.0 - s)))
        phi = 2.0 * PI * ((ti.cast(j, ti.f32) + fu) / self.width) - self.environment.scalars[1]
        local = ti.math.vec3(sin_theta * ti.sin(phi), z, -sin_theta * ti.cos(phi))
        # a rotation has a unit Jacobian: the pdf in the world is the map frame's
        direction = self.environment.from_map(local)
        return direction, self.texel_pdf[i, j], self.environment.radiance(direction)

    @ti.func
    def pdf(self, direction):
        """Solid-angle pdf of `sample` producing `direction` (unit vector); finite everywhere."""
        d = self.environment.to_map(direction)
        u = (ti.atan2(d.x, -d.z) + self.environment.scalars[1]) / (2.0 * PI)
        u -= ti.floor(u)
        # theta by atan2: accurate near the poles, where acos(y) loses digits
        theta = ti.atan2(ti.sqrt(d.x * d.x + d.z * d.z), d.y)
        j = ti.math.clamp(ti.cast(u * self.width, ti.i32), 0, self.width - 1)
        # the row whose centre, pi i / (H - 1), is nearest
        i = ti.math.clamp(ti.cast(theta * (1.0 / PI) * (self.height - 1) + 0.5, ti.i32), 0, self.height - 1)
        return self.texel_pdf[i, j]

    # -- host helpers (tests, benchmarks) --------------------------------------------------------

    @ti.kernel
    def _sample_kernel(self, u: ti.types.ndarray(dtype=ti.math.vec2, ndim=1),
                       directions: ti.types.ndarray(dtype=ti.math.vec3, ndim=1),
                       pdfs: ti.types.ndarray(dtype=ti.f32, ndim=1),
                       radiance: ti.types.ndarray(dtype=ti.math.vec3, ndim=1)):
        for k in range(u.shape[0]):
            d, p, r = self.sample(u[k])
            directions[k] = d
            pdfs[k] = p
            radiance[k] = r

    @ti.kernel
    def _pdf_kernel(self, directions: ti.types.ndarray(dtype=ti.math.vec3, ndim=1),
                    pdfs: ti.types.ndarray(dtype=ti.f32, ndim=1)):
        for k in range(directions.shape[0]):
            pdfs[k] = self.pdf(directions[k])

    @ti.kernel
    def _radiance_kernel(self, directions: ti.types.ndarray(dtype=ti.math.vec3, ndim=1),
                         radiance: ti.types.ndarray(dtype=ti.math.vec3, ndim=1)):
        for k in range(directions.shape[0]):
            radiance[k] = self.environment.radiance(directions[k])

    def sample_batch(self, u: np.ndarray):
        """u: (N, 2) -> directions (N, 3), pdf (N,), radiance (N, 3), all float32."""
        u = np.ascontiguousarray(u, np.float32).reshape(-1, 2)
        n = len(u)
        directions = np.zeros((n, 3), np.float32)
        pdfs = np.zeros(n, np.float32)
        radiance = np.zeros((n, 3), np.float32)
        self._sample_kernel(u, directions, pdfs, radiance)
        return directions, pdfs, radiance

    def pdf_batch(self, directions: np.ndarray) -> np.ndarray:
        directions = np.ascontiguousarray(directions, np.float32).reshape(-1, 3)
        pdfs = np.zeros(len(directions), np.float32)
        self._pdf_kernel(directions, pdfs)
        return pdfs

    def radiance_batch(self, directions: np.ndarray) -> np.ndarray:
        directions = np.ascontiguousarray(directions, np.float32).reshape(-1, 3)
        radiance = np.zeros((len(directions), 3), np.float32)
        self._radiance_kernel(directions, radiance)
        return radiance

    def texel_edges(self, rotation: float | None = None):
        """Discontinuities of the pdf: (phi edges, theta edges) in radians, phi as
        atan2(d.x, -d.z) in [0, 2 pi) for the given (default: current) rotation about the map's
        pole; in the map's frame where a full rotation is compiled in."""
        if rotation is None:
            rotation = float(self.environment.scalars[1])
        phi = np.mod(2.0 * math.pi * np.arange(self.width) / self.width - rotation, 2.0 * math.pi)
        return phi, row_edges(self.height)[1:-1]

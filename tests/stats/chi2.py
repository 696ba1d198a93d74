"""Chi-square goodness-of-fit test for direction samplers, after Mitsuba's `ChiSquareTest`.

The caller draws many directions with the sampler under test (on the device, passing them here as
numpy arrays) and supplies the sampler's pdf as a vectorised callable `pdf(dirs (N, 3)) -> (N,)`
in solid-angle measure. The harness

1. bins the sphere (or the hemisphere) into `2*res x res` equal-area cells in (phi, cos theta) and
   histograms the samples (the observed counts);
2. integrates the pdf over each cell numerically and multiplies by the sample count (the expected
   counts). Cells are integrated in (phi, theta) with the Jacobian sin(theta): equirectangular pdfs
   carry a 1/sin(theta) factor, integrable in cos(theta) but singular for a quadrature there,
   while pdf * sin(theta) is bounded. The quadrature is a tensor product of Gauss-Legendre rules on
   the cell edges merged with optional *break lines* (`phi_breaks`, `theta_breaks`): a
   piecewise-smooth pdf (a tabulated distribution such as an environment map) passes its
   discontinuities, and the integral is then exact to rounding instead of O(1/n);
3. adds two more categories of the multinomial: *failed* samples (`valid == False`, or outside the
   hemisphere), expected `N * (1 - pdf_integral - delta_probability)`, and *delta* samples (flagged
   by the caller, not binned), expected `N * delta_probability`;
4. pools categories with expected count < `min_expected` into one (merging the pool with the next
   smallest category while it is still below), computes Pearson's statistic, its p-value
   (`scipy.stats.chi2.sf`, dof = categories used - 1), and rejects when p < the Sidak-corrected
   significance `1 - (1 - alpha)^(1/num_tests)`.

It also fails outright (whatever the p-value) when samples land in a category whose expected count
is exactly 0, when the pdf is negative or not finite, or when the pdf does not integrate to
`1 - delta_probability` (to `integral_tolerance`) for a sampler declared lossless; a lossy sampler's
pdf may integrate to less, and its failure count is then what the failed category tests.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Callable

import numpy as np
from scipy import stats

TWO_PI = 2.0 * math.pi
Z_UP = np.eye(3)  # frame rows: local x, local y, pole (world = local @ frame)
ENV_FRAME = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
"""The environment map's frame: phi = atan2(d.x, -d.z), theta = acos(d.y) (pole = +y)."""


def sidak_alpha(alpha: float, num_tests: int) -> float:
    """Per-test significance so that `num_tests` independent tests reject a true null w.p. alpha."""
    if not 0.0 < alpha < 1.0 or num_tests < 1:
        raise ValueError("need 0 < alpha < 1 and num_tests >= 1")
    return 1.0 - (1.0 - alpha) ** (1.0 / num_tests)


@dataclasses.dataclass
class ChiSquareResult:
    passed: bool
    statistic: float
    dof: int
    p_value: float
    alpha: float
    alpha_sidak: float
    pdf_integral: float
    expected_integral: float  # 1 - delta_probability (what a lossless sampler's pdf integrates to)
    sample_count: int
    failed_count: int  # invalid samples plus valid ones outside the domain
    expected_failed: float
    out_of_domain: int
    delta_count: int
    expected_delta: float
    pooled_categories: int
    observed: np.ndarray  # (res, 2 * res): rows from the pole down in cos theta, columns in phi
    expected: np.ndarray
    domain: str
    messages: list[str]

    def __bool__(self) -> bool:
        return self.passed

    @property
    def report(self) -> str:
        verdict = "PASS" if self.passed else "FAIL"
        lines = [
            f"chi-square {verdict}: statistic {self.statistic:.2f}, dof {self.dof}, "
            f"p = {self.p_value:.4g} (alpha {self.alpha} -> Sidak {self.alpha_sidak:.3g})",
            f"{self.domain}, {self.observed.shape[1]}x{self.observed.shape[0]} cells, "
            f"{self.sample_count} samples; {self.pooled_categories} low-expectation categories pooled",
            f"pdf integral {self.pdf_integral:.6f} (lossless: {self.expected_integral:.6f})",
            f"failed samples {self.failed_count} (expected {self.expected_failed:.1f}; "
            f"{self.out_of_domain} outside the domain)",
        ]
        if self.delta_count or self.expected_delta:
            lines.append(f"delta samples {self.delta_count} (expected {self.expected_delta:.1f})")
        lines += [f"! {m}" for m in self.messages]
        return "\n".join(lines)

    def write_png(self, path) -> Path:
        return write_histograms_png(self, path)


def chi2_test(
    directions: np.ndarray,
    pdf: Callable[[np.ndarray], np.ndarray],
    *,
    valid: np.ndarray | None = None,
    delta: np.ndarray | None = None,
    delta_probability: float = 0.0,
    domain: str = "sphere",
    res: int = 32,
    frame: np.ndarray | None = None,
    alpha: float = 0.01,
    num_tests: int = 1,
    lossy: bool = False,
    integral_tolerance: float = 1e-3,
    min_expected: float = 5.0,
    quad_points: int = 4,
    subdivisions: int = 2,
    phi_breaks: np.ndarray | None = None,
    theta_breaks: np.ndarray | None = None,
    batch: int = 1 << 20,
) -> ChiSquareResult:
    """Test samples `directions` (N, 3) against `pdf` (solid angle). See the module doc.

    valid: (N,) bool, False for samples the sampler failed to produce (default: all valid).
    delta: (N,) bool, True for samples of a delta component (not binned); `delta_probability` is
        the probability the sampler picks it. The callable pdf covers the non-delta part only.
    domain: "sphere" or "hemisphere" (cos theta >= 0 about the frame's pole).
    frame: 3x3, rows = local x axis, local y axis, pole, in world coordinates; phi is measured
        as atan2(local y, local x) in [0, 2 pi). Default: z is the pole.
    lossy: the sampler may fail; its pdf then integrates to its success probability.
    phi_breaks, theta_breaks: known discontinuities of the pdf (radians, in the frame's phi and
        theta), merged into the quadrature grid.
    """
    if domain not in ("sphere", "hemisphere"):
        raise ValueError(f"domain must be 'sphere' or 'hemisphere', not {domain!r}")
    frame = Z_UP if frame is None else np.asarray(frame, np.float64)
    if frame.shape != (3, 3) or not np.allclose(frame @ frame.T, np.eye(3), atol=1e-9):
        raise ValueError("frame must be a 3x3 orthonormal matrix")
    directions = np.asarray(directions, np.float64).reshape(-1, 3)
    n = directions.shape[0]
    if n == 0:
        raise ValueError("no samples")
    valid = np.ones(n, bool) if valid is None else np.asarray(valid, bool).reshape(n)
    is_delta = np.zeros(n, bool) if delta is None else np.asarray(delta, bool).reshape(n)
    if not 0.0 <= delta_probability <= 1.0:
        raise ValueError("delta_probability must be in [0, 1]")
    alpha_sidak = sidak_alpha(alpha, num_tests)
    messages: list[str] = []
    hard_fail = False

    n_phi, n_cos = 2 * res, res
    cos_range = 2.0 if domain == "sphere" else 1.0

    # --- observed ---------------------------------------------------------------------------
    delta_count = int(np.count_nonzero(valid & is_delta))
    binned = valid & ~is_delta
    local = directions[binned] @ frame.T
    finite = np.isfinite(local).all(axis=1)
    norms = np.linalg.norm(local, axis=1)
    finite &= norms > 0.0
    if not finite.all():
        messages.append(f"{np.count_nonzero(~finite)} valid samples are not finite unit vectors")
        hard_fail = True
    local = local[finite] / norms[finite, None]
    cos_theta = np.clip(local[:, 2], -1.0, 1.0)
    inside = cos_theta >= 0.0 if domain == "hemisphere" else np.ones(len(local), bool)
    out_of_domain = int(np.count_nonzero(~inside))
    local, cos_theta = local[inside], cos_theta[inside]
    phi = np.mod(np.arctan2(local[:, 1], local[:, 0]), TWO_PI)
    ix = np.minimum((phi * (n_phi / TWO_PI)).astype(np.int64), n_phi - 1)
    iy = np.minimum(((1.0 - cos_theta) * (n_cos / cos_range)).astype(np.int64), n_cos - 1)
    observed = np.bincount(iy * n_phi + ix, minlength=n_phi * n_cos).reshape(n_cos, n_phi).astype(np.float64)
    failed_count = int(np.count_nonzero(~valid)) + out_of_domain + int(np.count_nonzero(~finite))

    # --- expected -----------------------------------------------------------------------------
    cell_integrals, pdf_problem = _integrate_cells(
        pdf, frame, n_phi, n_cos, cos_range, quad_points, subdivisions, phi_breaks, theta_breaks, batch
    )
    if pdf_problem:
        messages.append(pdf_problem)
        hard_fail = True
    pdf_integral = float(cell_integrals.sum())
    expected_integral = 1.0 - delta_probability
    if lossy:
        if pdf_integral > expected_integral + integral_tolerance:
            messages.append(f"pdf integrates to {pdf_integral:.6f} > {expected_integral:.6f}")
            hard_fail = True
    elif abs(pdf_integral - expected_integral) > integral_tolerance:
        messages.append(
            f"pdf integrates to {pdf_integral:.6f}, not {expected_integral:.6f} "
            f"(tolerance {integral_tolerance}; pass lossy=True if the sampler may fail)"
        )
        hard_fail = True
    expected = cell_integrals * n
    expected_delta = n * delta_probability
    # A lossless sampler must never fail; a lossy one fails with the probability its pdf leaves out.
    expected_failed = n * max(0.0, 1.0 - pdf_integral - delta_probability) if lossy else 0.0

    # --- statistic ----------------------------------------------------------------------------
    obs = [observed.ravel()]
    exp = [expected.ravel()]
    names = ["cells"]
    if expected_delta > 0.0 or delta_count:
        obs.append(np.array([delta_count], np.float64))
        exp.append(np.array([expected_delta]))
        names.append("delta")
    if expected_failed > 0.0 or failed_count:
        obs.append(np.array([failed_count], np.float64))
        exp.append(np.array([expected_failed]))
        names.append("failed")
    obs_all, exp_all = np.concatenate(obs), np.concatenate(exp)
    # "zero": below 1e-9 samples (quadrature rounding of a pdf that is 0 there)
    zero = (exp_all < 1e-9) & (obs_all > 0)
    if zero.any():
        cells_hit = int(np.count_nonzero(zero[: observed.size]))
        extra = [name for name, hit in zip(names[1:], zero[observed.size:]) if hit]
        what = f"{cells_hit} cells" + (f" and the {', '.join(extra)} category" if extra else "")
        messages.append(f"{int(obs_all[zero].sum())} samples fell where the expected count is 0 ({what})")
        hard_fail = True

    statistic, dof, pooled = _pearson(obs_all, exp_all, min_expected)
    if dof < 1:
        messages.append("fewer than two categories with enough expected samples: nothing to test")
        p_value = 0.0
        hard_fail = True
    else:
        p_value = float(stats.chi2.sf(statistic, dof))
    passed = (not hard_fail) and p_value >= alpha_sidak
    return ChiSquareResult(
        passed=passed, statistic=statistic, dof=dof, p_value=p_value, alpha=alpha,
        alpha_sidak=alpha_sidak, pdf_integral=pdf_integral, expected_integral=expected_integral,
        sample_count=n, failed_count=failed_count, expected_failed=expected_failed,
        out_of_domain=out_of_domain, delta_count=delta_count, expected_delta=expected_delta,
        pooled_categories=pooled, observed=observed, expected=expected, domain=domain,
        messages=messages,
    )


def integrate_pdf(pdf, *, domain="sphere", res=32, frame=None, quad_points=4, subdivisions=2,
                  phi_breaks=None, theta_breaks=None, batch=1 << 20) -> np.ndarray:
    """The integral of `pdf` over each cell of `chi2_test`'s grid, (res, 2 * res); its sum is the
    integral over the domain. Raises ValueError if the pdf is negative or not finite somewhere."""
    frame = Z_UP if frame is None else np.asarray(frame, np.float64)
    cos_range = 2.0 if domain == "sphere" else 1.0
    integrals, problem = _integrate_cells(pdf, frame, 2 * res, res, cos_range, quad_points, subdivisions,
                                          phi_breaks, theta_breaks, batch)
    if problem:
        raise ValueError(problem)
    return integrals


def _pearson(observed: np.ndarray, expected: np.ndarray, min_expected: float) -> tuple[float, int, int]:
    """Pearson's statistic with Mitsuba's pooling: categories with expectation below
    `min_expected` join one pool; while the pool is still below, it absorbs the next smallest
    category. Categories with zero expectation and no samples carry no information and are skipped.
    Returns (statistic, dof, number of categories pooled)."""
    keep = (expected >= 1e-9) | (observed > 0)
    order = np.argsort(expected[keep], kind="stable")
    e_sorted, o_sorted = expected[keep][order], observed[keep][order]
    small = e_sorted < min_expected
    pooled_e, pooled_o, pooled_n = float(e_sorted[small].sum()), float(o_sorted[small].sum()), int(small.sum())
    e_rest, o_rest = e_sorted[~small], o_sorted[~small]
    start = 0
    while pooled_n and pooled_e < min_expected and start < len(e_rest):
        pooled_e += e_rest[start]
        pooled_o += o_rest[start]
        pooled_n += 1
        start += 1
    e_rest, o_rest = e_rest[start:], o_rest[start:]
    statistic = float(np.sum((o_rest - e_rest) ** 2 / e_rest))
    categories = len(e_rest)
    if pooled_n and pooled_e > 0.0:
        statistic += (pooled_o - pooled_e) ** 2 / pooled_e
        categories += 1
    return statistic, categories - 1, pooled_n


def _gauss_nodes(edges: np.ndarray, quad_points: int, subdivisions: int):
    """Composite Gauss-Legendre nodes and weights on the intervals between sorted `edges`."""
    t, w = np.polynomial.legendre.leggauss(quad_points)
    a, b = edges[:-1], edges[1:]
    pieces = np.linspace(0.0, 1.0, subdivisions + 1)
    lo = (a[:, None] + (b - a)[:, None] * pieces[None, :-1]).ravel()
    hi = (a[:, None] + (b - a)[:, None] * pieces[None, 1:]).ravel()
    half = 0.5 * (hi - lo)
    nodes = (0.5 * (lo + hi))[:, None] + half[:, None] * t[None, :]
    weights = half[:, None] * w[None, :]
    midpoints = np.repeat(0.5 * (lo + hi), quad_points)
    return nodes.ravel(), weights.ravel(), midpoints


def _merge_breaks(edges: np.ndarray, breaks, lo: float, hi: float) -> np.ndarray:
    if breaks is None:
        return edges
    breaks = np.asarray(breaks, np.float64).ravel()
    breaks = breaks[(breaks > lo) & (breaks < hi)]
    merged = np.unique(np.concatenate([edges, breaks]))
    keep = np.concatenate([[True], np.diff(merged) > 1e-12])  # drop duplicates from rounding
    return merged[keep]


def _integrate_cells(pdf, frame, n_phi, n_cos, cos_range, quad_points, subdivisions,
                     phi_breaks, theta_breaks, batch):
    """Integral of pdf over each (cos theta, phi) cell: (n_cos, n_phi), plus a problem message."""
    phi_edges = np.linspace(0.0, TWO_PI, n_phi + 1)
    theta_edges = np.arccos(np.clip(1.0 - np.arange(n_cos + 1) * (cos_range / n_cos), -1.0, 1.0))
    theta_max = theta_edges[-1]
    wrapped = None if phi_breaks is None else np.mod(np.asarray(phi_breaks, np.float64), TWO_PI)
    phi_grid = _merge_breaks(phi_edges, wrapped, 0.0, TWO_PI)
    theta_grid = _merge_breaks(theta_edges, theta_breaks, 0.0, theta_max)
    phi_nodes, phi_weights, phi_mid = _gauss_nodes(phi_grid, quad_points, subdivisions)
    theta_nodes, theta_weights, theta_mid = _gauss_nodes(theta_grid, quad_points, subdivisions)
    phi_cell = np.clip(np.searchsorted(phi_edges, phi_mid, side="right") - 1, 0, n_phi - 1)
    theta_cell = np.clip(np.searchsorted(theta_edges, theta_mid, side="right") - 1, 0, n_cos - 1)
    # phi nodes are sorted, so each cell's nodes are contiguous: reduce with reduceat
    phi_starts = np.searchsorted(phi_cell, np.arange(n_phi))
    cos_phi, sin_phi = np.cos(phi_nodes), np.sin(phi_nodes)

    integrals = np.zeros((n_cos, n_phi))
    problem = ""
    rows_per_batch = max(1, batch // len(phi_nodes))
    for start in range(0, len(theta_nodes), rows_per_batch):
        th = theta_nodes[start:start + rows_per_batch]
        sin_t, cos_t = np.sin(th), np.cos(th)
        local = np.stack(
            [sin_t[:, None] * cos_phi[None, :], sin_t[:, None] * sin_phi[None, :],
             np.broadcast_to(cos_t[:, None], (len(th), len(phi_nodes)))], axis=-1
        ).reshape(-1, 3)
        values = np.asarray(pdf(local @ frame), np.float64).reshape(len(th), len(phi_nodes))
        bad = ~np.isfinite(values) | (values < 0.0)
        if bad.any() and not problem:
            problem = f"the pdf is negative or not finite at {np.count_nonzero(bad)} quadrature points"
        values = np.where(bad, 0.0, values)
        weighted = values * (sin_t * theta_weights[start:start + rows_per_batch])[:, None] * phi_weights[None, :]
        by_phi = np.add.reduceat(weighted, phi_starts, axis=1)
        np.add.at(integrals, theta_cell[start:start + rows_per_batch], by_phi)
    return integrals, problem


def write_histograms_png(result: ChiSquareResult, path) -> Path:
    """Observed, expected and (O - E) / sqrt(E) side by side, for looking at a failure."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = Figure(figsize=(15, 4.2), dpi=100)
    FigureCanvasAgg(fig)
    top = max(result.observed.max(), result.expected.max(), 1.0)
    residual = (result.observed - result.expected) / np.sqrt(np.maximum(result.expected, 1.0))
    limit = max(3.0, float(np.abs(residual).max()))
    extent = (0.0, 360.0, -1.0 if result.domain == "sphere" else 0.0, 1.0)
    panels = [
        ("observed", result.observed, dict(cmap="inferno", vmin=0.0, vmax=top)),
        ("expected", result.expected, dict(cmap="inferno", vmin=0.0, vmax=top)),
        ("(O - E) / sqrt(E)", residual, dict(cmap="coolwarm", vmin=-limit, vmax=limit)),
    ]
    for index, (title, data, style) in enumerate(panels):
        ax = fig.add_subplot(1, 3, index + 1)
        image = ax.imshow(data, extent=extent, aspect="auto", interpolation="nearest", **style)
        ax.set_title(title)
        ax.set_xlabel("phi (degrees)")
        ax.set_ylabel("cos theta")
        fig.colorbar(image, ax=ax)
    verdict = "PASS" if result.passed else "FAIL"
    fig.suptitle(f"{verdict}: chi2 {result.statistic:.1f}, dof {result.dof}, p {result.p_value:.3g}")
    fig.tight_layout()
    fig.savefig(path)
    return path

"""Solve the RGB -> spectrum basis of renderer/spectral/upsample.py and write it into that file.

The smoothest weights W (3 x BASIS_COUNT; basis spectrum c = sum_k W[c, k] N_k) subject to:
W >= 0 and sum_c W[c, k] = 1 (so the basis spectra lie in [0, 1] and sum to the constant 1,
because the B-splines N_k are non-negative and sum to 1 over the range), and RGB(R) = (1, 0, 0),
RGB(G) = (0, 1, 0) (then RGB(B) = (0, 0, 1) follows from RGB(1) = (1, 1, 1)). "Smoothest": the
least sum of squared second differences of each row of W. Solved with SLSQP from a feasible start
found by linear programming. Needs scipy (a test dependency, not a runtime one).

    .venv/bin/python scripts/make_rgb_spectrum_basis.py
"""
from __future__ import annotations

import re
import sys
import textwrap
from pathlib import Path

import numpy as np
from scipy.optimize import linprog, minimize

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from renderer.spectral import cie, upsample  # noqa: E402
from renderer.spectral.wavelengths import LAMBDA_MAX, LAMBDA_MIN  # noqa: E402


def spline_rgb() -> np.ndarray:
    """(3, K): the RGB of each B-spline as a spectrum (fine trapezoid quadrature, 0.01 nm)."""
    lam = np.linspace(LAMBDA_MIN, LAMBDA_MAX, 47001)
    splines = upsample.bspline_matrix_np(lam)  # (L, K)
    xyz = np.trapezoid(splines[:, :, None] * cie.cmf_xyz_np(lam)[:, None, :], lam, axis=0)  # (K, 3)
    return cie.SPECTRUM_TO_REC709 @ xyz.T


def solve() -> np.ndarray:
    k = upsample.BASIS_COUNT
    v = spline_rgb()
    # unknowns: rows R and G of W; B = 1 - R - G
    a_eq = np.zeros((6, 2 * k))
    b_eq = np.zeros(6)
    for row in range(2):
        a_eq[3 * row:3 * row + 3, row * k:(row + 1) * k] = v
        b_eq[3 * row + row] = 1.0
    a_ub = np.hstack([np.eye(k), np.eye(k)])  # R + G <= 1, i.e. B >= 0
    b_ub = np.ones(k)
    start = linprog(np.zeros(2 * k), A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq, bounds=[(0.0, 1.0)] * (2 * k))
    if start.status != 0:
        raise SystemExit(f"no feasible basis with {k} splines: {start.message}")
    d2 = np.diff(np.eye(k), 2, axis=0)

    def full(w):
        return np.stack([w[:k], w[k:], 1.0 - w[:k] - w[k:]])

    def roughness(w):
        return float(sum(np.sum((d2 @ row) ** 2) for row in full(w)))

    result = minimize(roughness, start.x, method="SLSQP", bounds=[(0.0, 1.0)] * (2 * k),
                      constraints=[{"type": "eq", "fun": lambda w: a_eq @ w - b_eq, "jac": lambda w: a_eq},
                                   {"type": "ineq", "fun": lambda w: b_ub - a_ub @ w, "jac": lambda w: -a_ub}],
                      options={"maxiter": 2000, "ftol": 1e-15})
    if not result.success:
        raise SystemExit(f"smoothing failed: {result.message}")
    w = np.clip(full(result.x), 0.0, 1.0)
    w[2] = 1.0 - w[0] - w[1]  # the partition of unity, after clipping
    return np.where(np.abs(w) < 1e-12, 0.0, w)  # rounding-level values (e.g. -5e-17) are 0


def write(w: np.ndarray) -> None:
    path = ROOT / "renderer" / "spectral" / "upsample.py"
    text = path.read_text()
    names = ("R", "G", "B")
    rows = []
    for name, row in zip(names, w):
        numbers = ", ".join(repr(float(f"{x:.12g}")) for x in row) + "),"
        body = textwrap.fill(numbers, width=110, initial_indent="     ", subsequent_indent="     ")
        rows.append(f"    # {name}\n    (" + body[5:])
    block = "WEIGHTS = (\n" + "\n".join(rows) + "\n)\n"
    new = re.sub(r"WEIGHTS = \(\n.*?\n\)\n", lambda m: block, text, count=1, flags=re.S)
    path.write_text(new)
    print(f"wrote {w.shape[1]} weights per channel to {path.relative_to(ROOT)}; roundtrip residual "
          f"{np.abs(spline_rgb() @ w.T - np.eye(3)).max():.2e}")


if __name__ == "__main__":
    write(solve())

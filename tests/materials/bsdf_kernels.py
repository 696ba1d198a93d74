"""Batched calls of the BSDF on the device, for the material tests.

`BsdfBench` owns a small material table (every kind compiled in; energy compensation as `features` says) and two kernels that run
`Bsdf.shade` + `Bsdf.sample` (with `Bsdf.eval` at the sampled direction) and `Bsdf.eval` over
arrays of samples in parallel. Materials are rows added on demand (`bench.material(spec)`);
adding a row re-uploads the table's data and compiles nothing, so a test module builds one bench
(in a module-scoped fixture) and every kernel compiles once for it.

Everything is in world space, as the integrators call it: `n` is the outward shading normal and
`wo` points back along the path. Arrays may be given per sample or broadcast from one value.
"""

import dataclasses

import numpy as np
import taichi as ti

from tests.stats.chi2 import chi2_test

from renderer.geometry.interface import Surface
from renderer.materials.bsdf import Bsdf
from renderer.materials.table import MaterialRows, MaterialTable
from renderer.scene.features import Features
from renderer.scene.description import MaterialSpec

vec3 = ti.math.vec3
ALL_KINDS = Features(material_kinds=frozenset({"diffuse", "conductor", "dielectric", "principled"}))


@ti.func
def _surface(material, n):
    return Surface(p=vec3(0.0), n_geo=n, n_shading=n, uv=ti.math.vec2(0.0), uv1=ti.math.vec2(0.0),
                   tangent=ti.math.vec4(0.0), material=material, prim=0, front_face=1, eps=0.0,
                   cone_width=0.0, cone_spread=0.0)


@ti.kernel
def _sample_kernel(bsdf: ti.template(), mat_id: ti.types.ndarray(dtype=ti.i32, ndim=1),
                   normal: ti.types.ndarray(dtype=vec3, ndim=1), wo: ti.types.ndarray(dtype=vec3, ndim=1),
                   u: ti.types.ndarray(dtype=vec3, ndim=1),
                   wi: ti.types.ndarray(dtype=vec3, ndim=1), weight: ti.types.ndarray(dtype=vec3, ndim=1),
                   pdf: ti.types.ndarray(dtype=ti.f32, ndim=1), delta: ti.types.ndarray(dtype=ti.i32, ndim=1),
                   valid: ti.types.ndarray(dtype=ti.i32, ndim=1),
                   eval_value: ti.types.ndarray(dtype=vec3, ndim=1),
                   eval_pdf: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(mat_id.shape[0]):
        mat, n = bsdf.shade(_surface(mat_id[i], normal[i]), wo[i])
        s = bsdf.sample(mat, n, wo[i], u[i].x, ti.math.vec2(u[i].y, u[i].z))
        wi[i] = s.wi
        weight[i] = s.weight
        pdf[i] = s.pdf
        delta[i] = s.delta
        valid[i] = s.valid
        value, p = bsdf.eval(mat, n, wo[i], s.wi)
        eval_value[i] = value
        eval_pdf[i] = p


@ti.kernel
def _eval_kernel(bsdf: ti.template(), mat_id: ti.types.ndarray(dtype=ti.i32, ndim=1),
                 normal: ti.types.ndarray(dtype=vec3, ndim=1), wo: ti.types.ndarray(dtype=vec3, ndim=1),
                 wi: ti.types.ndarray(dtype=vec3, ndim=1),
                 value: ti.types.ndarray(dtype=vec3, ndim=1), pdf: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(mat_id.shape[0]):
        mat, n = bsdf.shade(_surface(mat_id[i], normal[i]), wo[i])
        v, p = bsdf.eval(mat, n, wo[i], wi[i])
        value[i] = v
        pdf[i] = p


@dataclasses.dataclass
class Samples:
    wi: np.ndarray  # (N, 3) float32, world space
    weight: np.ndarray  # (N, 3) f |cos| / pdf
    pdf: np.ndarray  # (N,)
    delta: np.ndarray  # (N,) bool
    valid: np.ndarray  # (N,) bool
    eval_value: np.ndarray  # (N, 3) eval(wo, wi) at the sampled wi
    eval_pdf: np.ndarray  # (N,)


def _vec_rows(x, n) -> np.ndarray:
    a = np.asarray(x, np.float32)
    return np.ascontiguousarray(np.broadcast_to(a, (n, 3)) if a.ndim == 1 else a.reshape(n, 3))


class BsdfBench:
    """A material table with room for `capacity` materials and the BSDF over it."""

    def __init__(self, capacity: int = 128, features: Features = ALL_KINDS):
        self.capacity = capacity
        self.rows = MaterialRows()
        self.ids: dict[MaterialSpec, int] = {}
        filler = MaterialRows()
        for _ in range(capacity):
            filler.add_spec(MaterialSpec(name="unused"))
        self.table = MaterialTable(filler)
        self.bsdf = Bsdf(self.table, features)

    def material(self, spec: MaterialSpec) -> int:
        """The table index of `spec`, adding it (a data upload, no compilation) if it is new."""
        if spec not in self.ids:
            if len(self.ids) >= self.capacity:
                raise ValueError("material table full")
            self.ids[spec] = self.rows.add_spec(spec)
            arrays = self.rows.arrays()
            padded = {k: np.concatenate([v, np.repeat(v[-1:], self.capacity - len(v), axis=0)])
                      for k, v in arrays.items()}
            self.table.table.from_numpy(padded)
        return self.ids[spec]

    def sample(self, mat, normal, wo, u) -> Samples:
        """mat: a table index (int) or (N,) indices; normal, wo: (3,) or (N, 3); u: (N, 3) in [0, 1)
        (u[:, 0] picks the lobe, u[:, 1:] the direction)."""
        u = np.ascontiguousarray(u, np.float32).reshape(-1, 3)
        n = len(u)
        ids = np.ascontiguousarray(np.broadcast_to(np.asarray(mat, np.int32), (n,)))
        out = Samples(wi=np.zeros((n, 3), np.float32), weight=np.zeros((n, 3), np.float32),
                      pdf=np.zeros(n, np.float32), delta=np.zeros(n, np.int32), valid=np.zeros(n, np.int32),
                      eval_value=np.zeros((n, 3), np.float32), eval_pdf=np.zeros(n, np.float32))
        _sample_kernel(self.bsdf, ids, _vec_rows(normal, n), _vec_rows(wo, n), u, out.wi, out.weight, out.pdf,
                       out.delta, out.valid, out.eval_value, out.eval_pdf)
        out.delta = out.delta.astype(bool)
        out.valid = out.valid.astype(bool)
        return out

    def eval(self, mat, normal, wo, wi) -> tuple[np.ndarray, np.ndarray]:
        """(f |cos wi| (N, 3), pdf (N,)) at world directions wi (N, 3)."""
        wi = np.ascontiguousarray(wi, np.float32).reshape(-1, 3)
        n = len(wi)
        ids = np.ascontiguousarray(np.broadcast_to(np.asarray(mat, np.int32), (n,)))
        value = np.zeros((n, 3), np.float32)
        pdf = np.zeros(n, np.float32)
        _eval_kernel(self.bsdf, ids, _vec_rows(normal, n), _vec_rows(wo, n), wi, value, pdf)
        return value, pdf

    def pdf_callable(self, mat, normal, wo):
        """`pdf(directions (M, 3)) -> (M,)` in float64 for the chi-square harness."""
        return lambda d: self.eval(mat, normal, wo, d)[1].astype(np.float64)


class FixedBench(BsdfBench):
    """A bench whose table holds exactly the given materials, built with them (kinds whose rows
    carry tables made at the table's construction, as rough plastics, need it)."""

    def __init__(self, specs, features: Features):
        self.capacity = len(specs)
        self.rows = MaterialRows()
        self.ids = {spec: self.rows.add_spec(spec) for spec in specs}
        self.table = MaterialTable(self.rows)
        self.bsdf = Bsdf(self.table, features)


def uniforms(n: int, seed: int) -> np.ndarray:
    """(n, 3) float32 uniforms in [0, 1) from a fixed seed."""
    return np.random.default_rng(seed).random((n, 3), dtype=np.float32)


def direction(cos_theta: float, phi: float = 0.3) -> np.ndarray:
    """A unit vector (float64) at polar angle acos(cos_theta) from +z."""
    s = np.sqrt(max(0.0, 1.0 - cos_theta * cos_theta))
    return np.array([s * np.cos(phi), s * np.sin(phi), cos_theta])


def frame_about(pole) -> np.ndarray:
    """An orthonormal frame (rows: x, y, pole) for the chi-square harness."""
    z = np.asarray(pole, np.float64)
    z = z / np.linalg.norm(z)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


# --- expected cell probabilities for pdfs with jumps -----------------------------------------------
# The chi-square harness integrates the pdf over each cell with a fixed Gauss rule, which converges
# only as O(1/n) across a jump that does not follow a cell edge: the edge of a rough dielectric's
# transmission support (the image of horizontal microfacets, where GGX's D is still alpha^2 / pi),
# the outline of an emitter seen from a point. `cell_probabilities` integrates each cell adaptively
# instead (a quadtree in (phi, theta), refined where two Gauss rules disagree), and `binned_pdf`
# hands the result to the harness as a pdf that is constant on each of its cells, which its own rule
# integrates exactly: the expected counts are then the adaptive integrals. A feature smaller than the
# rule's node spacing (a narrow lobe at grazing incidence) can hide between all nodes; cells that
# look wrong after a first test are integrated again from a finer start (`cells`, `start_depth`;
# see `chi2_adaptive`): the target, the pdf's integral over the cell, is the same, only better
# resolved.

def _rect_integrals(pdf, frame, p0, p1, t0, t1, k, order):
    """Integral of pdf * sin(theta) over rectangles [p0, p1] x [t0, t1], each split k x k with an
    order x order Gauss-Legendre rule per piece. Returns (R,) and the number of bad values."""
    x, w = np.polynomial.legendre.leggauss(order)
    s = (np.arange(k)[:, None] + 0.5 * (x[None, :] + 1.0)).ravel() / k  # (k * order,) in (0, 1)
    ws = np.tile(w, k) * (0.5 / k)
    phi = p0[:, None] + (p1 - p0)[:, None] * s[None, :]
    th = t0[:, None] + (t1 - t0)[:, None] * s[None, :]
    wp = (p1 - p0)[:, None] * ws[None, :]
    wt = (t1 - t0)[:, None] * ws[None, :] * np.sin(th)
    st, ct = np.sin(th), np.cos(th)
    m = len(s)
    local = np.empty((len(p0), m, m, 3))
    local[..., 0] = st[:, :, None] * np.cos(phi)[:, None, :]
    local[..., 1] = st[:, :, None] * np.sin(phi)[:, None, :]
    local[..., 2] = ct[:, :, None]
    world = np.einsum("...i,ij->...j", local.reshape(-1, 3), frame)
    values = np.asarray(pdf(world), np.float64).reshape(len(p0), m, m)
    bad = ~np.isfinite(values) | (values < 0.0)
    values = np.where(bad, 0.0, values)
    return np.einsum("rt,rp,rtp->r", wt, wp, values), int(bad.sum())


def cell_probabilities(pdf, *, domain="sphere", res=32, frame=None, abs_tol=1e-7, max_depth=8, order=4,
                       cells=None, start_depth=0, theta_breaks=None):
    """(res, 2 res) integrals of `pdf` over the harness's cells (rows from the pole down in cos
    theta, columns in phi): a (sub)cell is accepted when its k = 1 and k = 2 rules agree to
    abs_tol / 2^depth, else it is split in four, down to `max_depth`. Smooth cells come out to about
    abs_tol; a cell crossed by a jump stops refining at max_depth along it, with an error of about
    jump x cell probability x 2^-max_depth (~1e-4 of the cell at depth 8).
    cells: optional (res, 2 res) bool mask of the cells to integrate (others are 0); start_depth:
    split every cell into 4^start_depth pieces first (to find features smaller than the rule);
    theta_breaks: known jumps along circles of constant theta (radians in the frame), made edges."""
    frame = np.eye(3) if frame is None else np.asarray(frame, np.float64)
    n_phi, n_cos = 2 * res, res
    cos_range = 2.0 if domain == "sphere" else 1.0
    phi_edges = np.linspace(0.0, 2.0 * np.pi, n_phi + 1)
    theta_edges = np.arccos(np.clip(1.0 - np.arange(n_cos + 1) * (cos_range / n_cos), -1.0, 1.0))
    theta_grid = theta_edges
    if theta_breaks is not None:
        extra = np.asarray(theta_breaks, np.float64).ravel()
        theta_grid = np.unique(np.concatenate([theta_edges, extra[(extra > 0.0) & (extra < theta_edges[-1])]]))
    row = np.clip(np.searchsorted(theta_edges, 0.5 * (theta_grid[:-1] + theta_grid[1:])) - 1, 0, n_cos - 1)
    piece, ix = np.meshgrid(np.arange(len(row)), np.arange(n_phi), indexing="ij")
    piece, ix = piece.ravel(), ix.ravel()
    iy = row[piece]
    chosen = np.ones(n_cos * n_phi, bool) if cells is None else np.asarray(cells, bool).ravel()
    keep = chosen[iy * n_phi + ix]
    piece, ix, iy = piece[keep], ix[keep], iy[keep]
    m = 2 ** start_depth
    a, b = np.meshgrid(np.arange(m), np.arange(m), indexing="ij")
    a, b = a.ravel()[None, :], b.ravel()[None, :]
    cell = np.repeat(iy * n_phi + ix, m * m)
    dp = ((phi_edges[ix + 1] - phi_edges[ix]) / m)[:, None]
    dt = ((theta_grid[piece + 1] - theta_grid[piece]) / m)[:, None]
    p0 = (phi_edges[ix][:, None] + a * dp).ravel()
    p1 = (phi_edges[ix][:, None] + (a + 1) * dp).ravel()
    t0 = (theta_grid[piece][:, None] + b * dt).ravel()
    t1 = (theta_grid[piece][:, None] + (b + 1) * dt).ravel()
    out = np.zeros(n_cos * n_phi)
    bad_total = 0
    for depth in range(start_depth, max_depth + 1):
        coarse, bad_c = _rect_integrals(pdf, frame, p0, p1, t0, t1, 1, order)
        fine, bad_f = _rect_integrals(pdf, frame, p0, p1, t0, t1, 2, order)
        bad_total += bad_c + bad_f
        done = np.abs(fine - coarse) <= abs_tol / 2.0 ** depth
        if depth == max_depth:
            done[:] = True
        np.add.at(out, cell[done], fine[done])
        if done.all():
            break
        keep = ~done
        pm, tm = 0.5 * (p0 + p1), 0.5 * (t0 + t1)
        p0, p1, t0, t1, cell = (np.concatenate(parts) for parts in (
            (p0[keep], pm[keep], p0[keep], pm[keep]), (pm[keep], p1[keep], pm[keep], p1[keep]),
            (t0[keep], t0[keep], tm[keep], tm[keep]), (tm[keep], tm[keep], t1[keep], t1[keep]),
            (cell[keep],) * 4))
    if bad_total:
        raise ValueError(f"the pdf is negative or not finite at {bad_total} quadrature points")
    return out.reshape(n_cos, n_phi)


def binned_pdf(probabilities, *, domain="sphere", frame=None):
    """A pdf constant on each harness cell, with the given cell probabilities (res, 2 res)."""
    frame = np.eye(3) if frame is None else np.asarray(frame, np.float64)
    n_cos, n_phi = probabilities.shape
    cos_range = 2.0 if domain == "sphere" else 1.0
    density = probabilities / ((2.0 * np.pi / n_phi) * (cos_range / n_cos))

    def pdf(d):
        local = np.einsum("ij,kj->ik", np.asarray(d, np.float64), frame)
        phi = np.mod(np.arctan2(local[:, 1], local[:, 0]), 2.0 * np.pi)
        ix = np.minimum((phi * (n_phi / (2.0 * np.pi))).astype(np.int64), n_phi - 1)
        iy = np.clip(((1.0 - local[:, 2]) * (n_cos / cos_range)).astype(np.int64), 0, n_cos - 1)
        return density[iy, ix]

    return pdf


def chi2_adaptive(directions, pdf, *, frame=None, domain="sphere", res=32, max_recheck=256, theta_breaks=None,
                  **kwargs):
    """`chi2_test` with expected counts from adaptive cell integrals of `pdf` (to 0.1 / N in smooth
    cells; see `cell_probabilities` for cells crossed by a jump).

    A feature thinner than a cell rule's node spacing (a narrow lobe, an outline clipping a cell's
    corner) can hide between all of its nodes. So after a first test, the cells that look wrong (they
    hold samples but expect fewer than 1e-3, or |O - E| > 4 sqrt(E + 1)) are integrated again from
    16 x 16 pieces, and the test is run on the better integrals. This cannot hide a real error: the
    target of the integration, the pdf's integral over each cell, is the same, only better resolved.
    At most `max_recheck` cells are integrated again (a real mismatch shows in many more)."""
    n = len(directions)
    probabilities = cell_probabilities(pdf, domain=domain, res=res, frame=frame, abs_tol=0.1 / n, start_depth=1,
                                       theta_breaks=theta_breaks)
    result = chi2_test(directions, binned_pdf(probabilities, domain=domain, frame=frame), frame=frame,
                       domain=domain, res=res, **kwargs)
    expected = probabilities * n
    suspect = (result.observed > 0) & (expected < 1e-3)
    suspect |= np.abs(result.observed - expected) > 4.0 * np.sqrt(expected + 1.0)
    if suspect.any() and suspect.sum() <= max_recheck:
        finer = cell_probabilities(pdf, domain=domain, res=res, frame=frame, abs_tol=0.1 / n, cells=suspect,
                                   start_depth=4, theta_breaks=theta_breaks)
        probabilities[suspect] = finer[suspect]
        result = chi2_test(directions, binned_pdf(probabilities, domain=domain, frame=frame), frame=frame,
                           domain=domain, res=res, **kwargs)
    return result

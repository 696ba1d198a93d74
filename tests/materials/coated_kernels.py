"""Direct calls of the coated kind's layered BSDF (renderer/materials/coated.py) on parameter rows,
without the material table, for tests/materials/test_coated.py: small kernels that compile fast."""
import numpy as np
import taichi as ti

from renderer.materials import coated
from renderer.materials.coated import CoatParams

vec3 = ti.math.vec3
FIELDS = ("eta", "alpha_x", "alpha_y", "base", "reflectance", "c_eta", "c_k", "c_alpha", "thickness", "albedo", "g",
          "max_depth", "n_samples")


@ti.kernel
def _sample_kernel(params: ti.template(), row: ti.i32, wo: ti.types.ndarray(dtype=vec3, ndim=1),
                   u: ti.types.ndarray(dtype=vec3, ndim=1), wi: ti.types.ndarray(dtype=vec3, ndim=1),
                   weight: ti.types.ndarray(dtype=vec3, ndim=1), pdf: ti.types.ndarray(dtype=ti.f32, ndim=1),
                   delta: ti.types.ndarray(dtype=ti.i32, ndim=1), valid: ti.types.ndarray(dtype=ti.i32, ndim=1)):
    for i in range(u.shape[0]):
        s = coated.sample_params(params[row], wo[i], u[i].x, ti.math.vec2(u[i].y, u[i].z))
        wi[i], weight[i], pdf[i], delta[i], valid[i] = s.wi, s.weight, s.pdf, s.delta, s.valid


@ti.kernel
def _f_kernel(params: ti.template(), row: ti.i32, wo: ti.types.ndarray(dtype=vec3, ndim=1),
              wi: ti.types.ndarray(dtype=vec3, ndim=1), f: ti.types.ndarray(dtype=vec3, ndim=1)):
    for i in range(wi.shape[0]):
        f[i] = coated.layered_f(params[row], wo[i], wi[i])


@ti.kernel
def _pdf_kernel(params: ti.template(), row: ti.i32, wo: ti.types.ndarray(dtype=vec3, ndim=1),
                wi: ti.types.ndarray(dtype=vec3, ndim=1), pdf: ti.types.ndarray(dtype=ti.f32, ndim=1)):
    for i in range(wi.shape[0]):
        pdf[i] = coated.layered_pdf(params[row], wo[i], wi[i])


def params_row(eta=1.5, alpha_x=0.0, alpha_y=None, base="diffuse", reflectance=(0.5, 0.5, 0.5), c_eta=(0.2, 0.9, 1.1),
               c_k=(3.9, 2.5, 2.1), c_alpha=0.0, thickness=0.01, albedo=(0.0, 0.0, 0.0), g=0.0, max_depth=10,
               n_samples=1) -> dict:
    """A CoatParams row in pbrt's terms: widths alpha (not perceptual roughness), the conductor's
    index relative to the coat, pbrt's defaults."""
    return dict(eta=eta, alpha_x=alpha_x, alpha_y=alpha_x if alpha_y is None else alpha_y,
                base=coated.COAT_BASES[base], reflectance=reflectance, c_eta=c_eta, c_k=c_k, c_alpha=c_alpha,
                thickness=max(thickness, 1.1754944e-38), albedo=albedo, g=g, max_depth=max_depth,
                n_samples=n_samples)


def _rows(n, a):
    a = np.asarray(a, np.float32)
    return np.ascontiguousarray(np.broadcast_to(a, (n, 3)) if a.ndim == 1 else a.reshape(n, 3))


class CoatBench:
    """A field of CoatParams rows and the three kernels over it (local frame: z = the normal on
    wo's side)."""

    def __init__(self, rows: list[dict]):
        self.rows = rows
        self.field = CoatParams.field(shape=len(rows))
        for i, r in enumerate(rows):
            self.field[i] = dict(r)

    def sample(self, row, wo, u):
        u = np.ascontiguousarray(u, np.float32).reshape(-1, 3)
        n = len(u)
        out = dict(wi=np.zeros((n, 3), np.float32), weight=np.zeros((n, 3), np.float32), pdf=np.zeros(n, np.float32),
                   delta=np.zeros(n, np.int32), valid=np.zeros(n, np.int32))
        _sample_kernel(self.field, row, _rows(n, wo), u, out["wi"], out["weight"], out["pdf"], out["delta"],
                       out["valid"])
        return out

    def f(self, row, wo, wi):
        wi = np.ascontiguousarray(wi, np.float32).reshape(-1, 3)
        out = np.zeros((len(wi), 3), np.float32)
        _f_kernel(self.field, row, _rows(len(wi), wo), wi, out)
        return out

    def pdf(self, row, wo, wi):
        wi = np.ascontiguousarray(wi, np.float32).reshape(-1, 3)
        out = np.zeros(len(wi), np.float32)
        _pdf_kernel(self.field, row, _rows(len(wi), wo), wi, out)
        return out

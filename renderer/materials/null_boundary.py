"""The `null` kind: an invisible boundary (of a medium, say). Light goes straight on and nothing
changes; it has no non-delta part. Lobe module of renderer/materials/kinds.py (see diffuse.py)."""
import taichi as ti

from renderer.materials.kinds import LobeFlags
from renderer.materials.lobes import BsdfSample

vec3 = ti.math.vec3


@ti.func
def sample(bsdf, mat, n_f, t, b, entering, wo, u1, u2):
    return BsdfSample(wi=-wo, weight=vec3(1.0), pdf=1.0, delta=1, valid=1)


@ti.func
def evaluate(bsdf, mat, n_f, t, b, entering, wo, wi):
    return vec3(0.0), 0.0


@ti.func
def flags(bsdf, mat):
    return LobeFlags.TRANSMISSION | LobeFlags.SPECULAR

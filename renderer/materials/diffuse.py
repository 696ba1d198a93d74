"""The `diffuse` kind: Lambert reflection. The template of a kind's lobe module: `sample`,
`evaluate` and `flags` with these signatures, dispatched to by renderer/materials/bsdf.py for
the kind that renderer/materials/kinds.py names this module for. Vectors are local (z = the
shading normal on wo's side); n_f, t, b: that frame in world space; entering: wo is on the
side the normal points to."""
import taichi as ti

from renderer.materials import lobes
from renderer.materials.kinds import LobeFlags


@ti.func
def sample(bsdf, mat, n_f, t, b, entering, wo, u1, u2):
    return lobes.diffuse_sample(mat.base_color, wo, u2)


@ti.func
def evaluate(bsdf, mat, n_f, t, b, entering, wo, wi):
    return lobes.diffuse_eval(mat.base_color, wo, wi)


@ti.func
def flags(bsdf, mat):
    return LobeFlags.REFLECTION | LobeFlags.DIFFUSE

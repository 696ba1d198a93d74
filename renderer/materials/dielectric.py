"""The `dielectric` kind: smooth or rough glass, or a thin wall (`thin`), tinted by base_color;
the lobes are the Bsdf's glass lobes, which the principled model's transmission shares. Lobe
module of renderer/materials/kinds.py (see diffuse.py)."""
import taichi as ti

from renderer.materials.kinds import LobeFlags


@ti.func
def sample(bsdf, mat, n_f, t, b, entering, wo, u1, u2):
    return bsdf.glass_sample(mat, entering, wo, u1, u2)


@ti.func
def evaluate(bsdf, mat, n_f, t, b, entering, wo, wi):
    return bsdf.glass_eval(mat, entering, wo, wi)


@ti.func
def flags(bsdf, mat):
    return (LobeFlags.REFLECTION | LobeFlags.TRANSMISSION
            | (LobeFlags.GLOSSY if mat.alpha > 0.0 else LobeFlags.SPECULAR))

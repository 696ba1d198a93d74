"""The `dielectric` kind: smooth or rough glass, or a thin wall (`thin`), its transmission tinted
by base_color and its reflection by specular_color;
the lobes are the Bsdf's glass lobes, which the principled model's transmission shares. Lobe
module of renderer/materials/kinds.py (see diffuse.py)."""
import taichi as ti

from renderer.materials.kinds import LobeFlags


@ti.func
def sample(bsdf, mat, n_f, t, b, entering, wo, u1, u2):
    s = bsdf.glass_sample(mat, entering, wo, u1, u2)
    if s.wi.z > 0.0:
        s.weight *= mat.specular_color  # the reflection's tint (Mitsuba's specular_reflectance)
    return s


@ti.func
def evaluate(bsdf, mat, n_f, t, b, entering, wo, wi):
    value, pdf = bsdf.glass_eval(mat, entering, wo, wi)
    if wi.z > 0.0:
        value *= mat.specular_color
    return value, pdf


@ti.func
def flags(bsdf, mat):
    return (LobeFlags.REFLECTION | LobeFlags.TRANSMISSION
            | (LobeFlags.GLOSSY if mat.alpha > 0.0 else LobeFlags.SPECULAR))

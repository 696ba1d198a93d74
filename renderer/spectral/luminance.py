"""Rec.709 luminance: the one definition of its weights, for every part that weighs colours by
brightness (the film's noise estimate, tone mapping, emitter power, environment sampling, the
principled material's lobe choice)."""
import taichi as ti

LUMINANCE_WEIGHTS = (0.2126, 0.7152, 0.0722)  # Rec.709 / sRGB primaries


@ti.func
def luminance(rgb):
    return LUMINANCE_WEIGHTS[0] * rgb[0] + LUMINANCE_WEIGHTS[1] * rgb[1] + LUMINANCE_WEIGHTS[2] * rgb[2]

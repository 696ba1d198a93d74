"""`nee` and `mis`: path tracing with direct light sampling at every vertex.

`nee` takes direct light from light samples only: a BSDF-sampled ray that lands on an emitter the
lights can sample adds nothing (that light was counted already), except after a delta bounce,
which light sampling cannot follow. `mis` counts both strategies, each weighted by the power
heuristic (Veach 1997), so whichever samples a light better dominates: light sampling for small
lights and diffuse surfaces, BSDF sampling for large lights and glossy surfaces.
The tracer itself (one loop for every ray of a path, media) is renderer/integrators/tracer.py.
"""
import taichi as ti

from renderer.integrators.tracer import PathTracerBase

__all__ = ["NextEventEstimation", "MultipleImportanceSampling"]


@ti.data_oriented
class NextEventEstimation(PathTracerBase):
    name = "nee"
    hotkey = "j"  # next to "k" (mis)
    description = "path tracing with light sampling for direct light"
    mis = False


@ti.data_oriented
class MultipleImportanceSampling(PathTracerBase):
    name = "mis"
    hotkey = "k"
    description = "light and BSDF sampling combined by the power heuristic (the default)"
    mis = True

"""`path`: unidirectional path tracing with BSDF sampling only, and Russian roulette."""
import taichi as ti

from renderer.integrators.tracer import PathTracerBase

__all__ = ["PathTracer"]


@ti.data_oriented
class PathTracer(PathTracerBase):
    name = "path"
    hotkey = "t"  # "trace"
    description = "path tracing, BSDF sampling only"
    light_sampling = False  # (so `mis` is never read)
    uses_lights = False

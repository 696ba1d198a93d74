"""`path`: unidirectional path tracing with BSDF sampling only, and Russian roulette."""
import taichi as ti

from renderer.integrators.tracer import MAX_VERTICES, RR_DEPTH, PathTracerBase

__all__ = ["MAX_VERTICES", "RR_DEPTH", "PathTracer"]


@ti.data_oriented
class PathTracer(PathTracerBase):
    name = "path"
    hotkey = "t"  # "trace"
    description = "path tracing, BSDF sampling only"
    light_sampling = False
    mis = False
    uses_lights = False

"""SDF primitives and operators, sphere tracing, and the SDF side of the geometry interface."""

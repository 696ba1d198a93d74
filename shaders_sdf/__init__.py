"""SDF shading: the geometry contract implemented by sphere tracing a signed distance field.

It depends only downward: Taichi, numpy and the geometry contract it implements
(renderer.geometry.interface, emitter_shapes) plus renderer.runtime.upload. The renderer imports
it; nothing here imports a module that imports it back (tests/test_layout.py checks).

primitives.py         exact distance functions of the eight primitives
scene_sdf.py          the scene's SDF tree -> Taichi funcs (shapes compiled in, nodes as data),
                      the operators
geometry.py           `SdfGeometry`: sphere tracing with over-relaxation, normals, spawn offsets,
                      emissive spheres
"""

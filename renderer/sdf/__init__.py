"""SDF scenes: the geometry interface implemented by sphere tracing a signed distance field.

primitives.py         exact distance functions of the eight primitives
scene_sdf.py          the scene's SDF tree -> Taichi funcs (shapes compiled in, nodes as data)
geometry.py           `SdfGeometry`: sphere tracing with over-relaxation, normals, spawn offsets,
                      emissive spheres
"""

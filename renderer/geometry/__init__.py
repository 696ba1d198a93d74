"""Geometry: the contract every geometry kind implements, and the mesh world that implements it.

interface.py          Ray / Hit / Surface and the funcs a geometry object provides (the SDF side is
                      shaders_sdf)
mesh_data.py          a mesh scene's primitives as flat numpy arrays (triangles, spheres, quads,
                      discs, Bezier patches)
bvh_build.py          the BVH build (numpy): bvh_input.py checks its input, bvh_split.py splits each
                      level's nodes, bvh_tree.py is the tree it gives; box_rounding.py keeps its
                      f32 boxes conservative
instance_bvh.py       the two-level BVH of instanced meshes; instances.py their device data
mesh_geometry.py      the device side: traversal (stack, stackless, wide4 or wide8), hits, surfaces, emitter points
wide_bvh.py           the binary tree collapsed into 4- or 8-wide nodes (numpy); wide_traversal.py its device side
intersect.py          ray / primitive tests; coverage.py glTF alpha coverage during traversal
bezier.py             Bezier surfaces of revolution (numpy); bezier_newton.py, bezier_device.py
                      their ray test and device data
emitter_shapes.py     points on emissive shapes and their solid-angle densities
shading.py            shading normals kept consistent with the geometry
"""

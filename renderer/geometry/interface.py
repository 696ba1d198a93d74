"""The contract between integrators and geometry, SDF or mesh alike.

A geometry object provides these Taichi funcs:
  intersect(ray, t_max) -> Hit          closest hit along ray.d in (0, t_max)
  occluded(ray, t_max) -> bool          any hit in (0, t_max): shadow rays stop at the first
  trace(ray, t_max, any_hit) -> Hit     intersect, or (any_hit, a per-ray value) occluded's search
  surface(ray, hit) -> Surface          what the integrator shades
  spawn(surface, direction) -> Ray      a ray leaving the surface, offset so it cannot hit itself
  visible(surface, p, n) -> bool        nothing blocks the segment from the surface to point p
                                        (itself on a surface with normal n)
  next_segment(surface, d, p, n, to_p) -> (Ray, t_max)
                                        spawn's ray along d (t_max INF), or visible's shadow ray
                                        to p (to_p true; t_max <= 0: nothing to trace), so that an
                                        integrator traces both at one intersect call site;
                                        from a MEDIUM_POINT (eps < 0) rays start at p itself
  sample_emitter(prim, ref, u2) -> EmitterPoint        a point on emissive primitive `prim`
  emitter_pdf(prim, ref, p, n) -> f32   the solid-angle density sample_emitter gives point p
Integrators, materials, lights, camera and film never know which kind they run on.
On the host, both kinds say which object of the scene file a primitive belongs to (picking):
  objects_of(prims) -> array            the scene object of each primitive id, -1 for a miss (-1)

Rays carry a cone (width at the origin, spread per metre) so that the SDF marcher can grow its
hit threshold with the pixel footprint; mesh geometry turns it into the footprint that mip-mapped
texture lookups filter over (Surface.uv_footprint).
"""
import numpy as np
import taichi as ti

vec3 = ti.math.vec3

Ray = ti.types.struct(o=vec3, d=vec3, cone_width=ti.f32, cone_spread=ti.f32)

# `work` counts the geometry's own effort for the debug views and benchmarks: march steps for SDF
# scenes, node visits for BVH scenes; `tests` counts primitive tests (BVH only). `inside` is 1
# when the ray reached the surface from inside a solid (it leaves it there).
# `prim` and `bary` locate the hit on a mesh primitive (global id, two surface coordinates);
# `instance` is the mesh instance it belongs to (-1: a primitive placed in world space; read only
# by geometry with instances).
Hit = ti.types.struct(hit=ti.i32, t=ti.f32, work=ti.i32, tests=ti.i32, inside=ti.i32, prim=ti.i32,
                      bary=ti.math.vec2, instance=ti.i32)

# n_geo: outward geometric normal; n_shading: outward shading normal; eps: the distance within
# which a spawned ray must not find this surface again.
# uv / uv1: texture coordinate sets 0 and 1; tangent: xyz along +u and handedness w (0 when none).
# prim: what was hit (global primitive id on meshes, node id on SDF scenes): the key of emitters.
# color: the vertex colour at the point, linear RGBA (glTF COLOR_0, PLY colours), read only by
# kernels compiled with Features.has_vertex_colors; geometry without colours sets (1, 1, 1, 1).
# dp_du, dp_dv: the partial derivatives of the point along texture coordinates set 0 (Mitsuba's
# frame for its normal and bump maps), set only by geometry whose material rows need them
# (renderer/geometry/uv_partials.py); zero elsewhere (a struct's unnamed members start at zero).
# uv_footprint: the pixel's footprint in texture coordinates set 0, (du, dv) of its two axes
# (renderer/geometry/texture_footprint.py), set only by geometry whose textures are mip-mapped.
Surface = ti.types.struct(p=vec3, n_geo=vec3, n_shading=vec3, uv=ti.math.vec2, uv1=ti.math.vec2,
                          tangent=ti.math.vec4, material=ti.i32, prim=ti.i32, front_face=ti.i32, eps=ti.f32,
                          cone_width=ti.f32, cone_spread=ti.f32, color=ti.math.vec4, dp_du=vec3, dp_dv=vec3,
                          uv_footprint=ti.math.vec4)

# A point chosen on an emitter for direct lighting: position, outward normal, texture coordinates,
# and the solid-angle density of choosing it as seen from the reference point (0 if impossible).
EmitterPoint = ti.types.struct(p=vec3, n=vec3, uv=ti.math.vec2, pdf=ti.f32)

INF = 1e30  # "no hit yet"; far beyond any scene extent and still finite in f32
# Surface.eps of a point inside a medium, not on any surface: next_segment starts rays exactly
# there (a surface's spawn offset would be wrong where there is no surface to leave).
MEDIUM_POINT = -1.0


def owners_of(ids, owners) -> np.ndarray:
    """owners[id] for each id (an array of any shape), -1 where an id is out of range (a miss)."""
    ids = np.asarray(ids)
    inside = (ids >= 0) & (ids < len(owners))
    out = np.full(ids.shape, -1, np.int32)
    out[inside] = np.asarray(owners, np.int32)[ids[inside]]
    return out

"""glTF alpha coverage, tested where rays meet triangles, so that every ray (camera, continuation,
shadow, photon) sees the same holes.

alpha = the material's base alpha x the base-colour texture's alpha at the hit's texture
coordinates x the vertex colour's alpha. MASK: the hit stands where alpha >= the cutoff. BLEND:
stochastic coverage, the hit stands with probability alpha (pbrt-v4's approach): the uniform is
a hash of the world ray and the primitive, so one ray always decides alike for one primitive,
and rays sampled independently decide independently, which makes the path tracer converge to
the blended image. OPAQUE ignores alpha. Compiled only into scenes whose materials use MASK or
BLEND (MeshGeometry.has_alpha).
"""
import taichi as ti

from renderer.materials.table import ALPHA_MASK, ALPHA_OPAQUE, NO_TEXTURE
from renderer.sampling.rng import pcg_hash, uniform


@ti.func
def ray_primitive_uniform(o, d, g, instance):
    """A uniform number in [0, 1) that depends only on the ray (origin, direction), the
    primitive and the instance it belongs to (-1: none)."""
    h = pcg_hash(ti.cast(g, ti.u32) ^ pcg_hash(ti.cast(instance, ti.u32)))
    for i in ti.static(range(3)):
        h = pcg_hash(h ^ ti.bit_cast(o[i], ti.u32))
        h = pcg_hash(h ^ ti.bit_cast(d[i], ti.u32))
    return uniform(h, 0)


@ti.func
def covered(geometry: ti.template(), g, bary, o, d, instance):
    """1 when the hit of triangle g at barycentrics bary (of corners 1, 2) by the world ray
    (o, d) stands under its material's coverage, else 0. Other primitives are always covered."""
    keep = 1
    if g < geometry.range_end[0]:
        m = geometry.prim_material[g]
        mode = geometry.materials.table[m].alpha_mode
        if mode != ALPHA_OPAQUE:
            alpha = geometry.materials.table[m].base_alpha
            if ti.static(geometry.materials.textures.count > 0):
                slot = geometry.materials.table[m].textures[0]
                if slot != NO_TEXTURE:
                    uv, uv1 = geometry.texture_coordinates(g, bary)
                    alpha *= geometry.materials.textures.sample(slot, uv, uv1).w
            if ti.static(geometry.has_colors):
                alpha *= geometry.corners(geometry.tri_color, g, bary).w
            if mode == ALPHA_MASK:
                keep = 1 if alpha >= geometry.materials.table[m].alpha_cutoff else 0
            else:
                keep = 1 if ray_primitive_uniform(o, d, g, instance) < alpha else 0
    return keep

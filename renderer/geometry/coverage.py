"""Coverage (glTF alpha, Mitsuba's mask, back-face culling), tested where rays meet primitives, so
that every ray (camera, continuation, shadow, photon) sees the same holes.

alpha = the material's base alpha x the base-colour texture's alpha at the hit's texture
coordinates x the vertex colour's alpha. MASK: the hit stands where alpha >= the cutoff. BLEND:
stochastic coverage, the hit stands with probability alpha (pbrt-v4's approach): the uniform is
a hash of the world ray and the primitive, so one ray always decides alike for one primitive,
and rays sampled independently decide independently, which makes the path tracer converge to
the blended image. OPAQUE ignores alpha. Mitsuba's mask BSDF is BLEND with the alpha of its
opacity texture's first channel. A back-face-culled material (glTF doubleSided: false) is not
there for rays that meet its triangles from behind. Which side that is depends on the direction a
ray is traced, so culling, unlike alpha, is not symmetric: a path from the camera passes a culled
face from behind, while a point in front of the face still sees it, so the face shadows what it
faces. Photons (SPPM) travel against the paths' direction: they pass the face where paths stop at
it and stop where paths pass, so SPPM does not converge to the path tracers' image where light
crosses a culled face. Compiled only into scenes whose materials use MASK, BLEND or culling
(MeshGeometry.has_alpha).
"""
import taichi as ti

from renderer.materials.kinds import BACK_CULLED
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
def covered(geometry: ti.template(), g, bary, o, d, instance, d_local):
    """1 when the hit of primitive g at surface coordinates bary (a triangle's barycentrics of
    corners 1, 2; a quad's edge parameters) by the world ray (o, d), d_local in the primitive's
    frame, stands under its material's coverage, else 0. Textures vary the coverage of triangles
    and quads; spheres and discs take the material's constant alpha."""
    keep = 1
    m = geometry.prim_material[g]
    mode = geometry.materials.table[m].alpha_mode
    if geometry.materials.table[m].sidedness == BACK_CULLED:
        if _facing_away(geometry, g, d_local):
            keep = 0
    if mode != ALPHA_OPAQUE and keep == 1:
        alpha = geometry.materials.table[m].base_alpha
        if ti.static(geometry.materials.textures.count > 0):
            uv, uv1, textured = _texture_coordinates(geometry, g, bary)
            if textured:
                slot = geometry.materials.table[m].textures[0]
                if slot != NO_TEXTURE:
                    alpha *= geometry.materials.textures.sample(slot, uv, uv1).w
                opacity = geometry.materials.table[m].opacity_texture
                if opacity != NO_TEXTURE:
                    alpha *= geometry.materials.textures.sample(opacity, uv, uv1).x
        if ti.static(geometry.has_colors and "triangle" in geometry.kinds):
            if g < geometry.range_end[0]:
                alpha *= geometry.corners(geometry.tri_color, g, bary).w
        if mode == ALPHA_MASK:
            keep = 1 if alpha >= geometry.materials.table[m].alpha_cutoff else 0
        else:
            keep = 1 if ray_primitive_uniform(o, d, g, instance) < alpha else 0
    return keep


@ti.func
def _texture_coordinates(geometry: ti.template(), g, bary):
    """(uv, uv1, whether the primitive has texture coordinates here): a triangle's interpolated,
    a quad's edge parameters (as its surface gives them)."""
    uv, uv1 = ti.math.vec2(0.0), ti.math.vec2(0.0)
    textured = False
    if ti.static("triangle" in geometry.kinds):
        if g < geometry.range_end[0]:
            uv, uv1 = geometry.texture_coordinates(g, bary)
            textured = True
    if ti.static("quad" in geometry.kinds):
        if g >= geometry.range_end[1] and g < geometry.range_end[2]:
            uv = bary
            textured = True
    return uv, uv1, textured


@ti.func
def _facing_away(geometry: ti.template(), g, d_local):
    """Whether direction d_local meets primitive g's back face (triangles by their winding, quads
    by their edges' cross product; other primitives are closed and never culled)."""
    away = False
    if ti.static("triangle" in geometry.kinds):
        if g < geometry.range_end[0]:
            v0, v1, v2 = geometry.corners_of(g)
            away = (v1 - v0).cross(v2 - v0).dot(d_local) > 0.0
    if ti.static("quad" in geometry.kinds):
        if g >= geometry.range_end[1] and g < geometry.range_end[2]:
            i = g - geometry.range_end[1]
            away = geometry.quads[i, 1].cross(geometry.quads[i, 2]).dot(d_local) > 0.0
            if ti.static(geometry.has_flipped):
                if geometry.is_flipped(g):  # turned over (flip_normals): its front is the other side
                    away = not away
    return away

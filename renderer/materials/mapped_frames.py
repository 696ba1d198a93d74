"""Mitsuba 3's normalmap and bumpmap on the device: the shading normal a map gives, and the
weight Mitsuba puts on every scattering through such a normal.

Both work in the surface's shading frame as Mitsuba builds it: the shading normal n0, the tangent
s0 = dp/du made orthogonal to n0 (Surface.dp_du, renderer/geometry/uv_partials.py) and
t0 = n0 x s0.
  normalmap: the texture's raw RGB gives the normal 2 rgb - 1 in (s0, t0, n0).
  bumpmap:   the height texture's gradient in uv times the scale lifts the partials,
             dp/du' = dp/du + n0 (scale dh/du - n0 . dp/du) (and dp/dv' alike), and the normal is
             dp/du' x dp/dv' on the geometric normal's side.
Where the viewer is on the other side of the mapped normal than of n0, the mapped normal's
tangential part is mirrored (Mitsuba's flip_invalid_normals). Scattering then goes through the
inner BSDF in the mapped frame, and every value is weighted by `scattering_weight`: zero where
the light direction is on different sides of n0 and of the mapped normal, else the shadowing term
of Estevez et al. ("A Microfacet-Based Shadowing Function to Solve the Bump Terminator Problem",
Ray Tracing Gems 2019), which Mitsuba applies by default. A surface seen from behind (a two-sided
material) takes the map in the frame mirrored through its tangent plane, as Mitsuba's twosided does.
"""
import taichi as ti

from renderer.materials.kinds import BACK_BLACK, HEIGHT_MAP
from renderer.sampling.warps import orthonormal_basis, to_local
from renderer.spectral.luminance import luminance

vec3 = ti.math.vec3
# Squared lengths below which a vector has no usable direction (f32).
_TINY = 1e-30


@ti.func
def frame_tangent(n0, dp_du):
    """Mitsuba's shading tangent: dp/du made orthogonal to n0 and unit, or an arbitrary tangent
    where the surface has no dp/du."""
    s, _ = orthonormal_basis(n0)
    along = dp_du - n0 * n0.dot(dp_du)
    if along.dot(along) > _TINY:
        s = ti.math.normalize(along)
    return s


@ti.func
def _height_normal(tex, slot, scale, surface, n0):
    """The bumped normal in world space (n0 where the lifted partials are parallel)."""
    d_du, d_dv = tex.gradient(slot, surface.uv, surface.uv1)
    du = scale * luminance(d_du.xyz)
    dv = scale * luminance(d_dv.xyz)
    a = surface.dp_du + n0 * (du - n0.dot(surface.dp_du))
    b = surface.dp_dv + n0 * (dv - n0.dot(surface.dp_dv))
    n = a.cross(b)
    result = n0
    if n.dot(n) > _TINY:
        result = ti.math.normalize(n)
        if result.dot(surface.n_geo) < 0.0:
            result = -result
    return result


@ti.func
def mapped_frame(tex, slot, model, scale, surface, wo, has_height_maps: ti.template()):
    """(mapped normal, its tangent, n0 on the viewer's side) at the surface, for a row whose
    normal slot `slot` holds a map of NORMAL_MAP_MODELS `model` (shading frame or height)."""
    n0 = surface.n_shading
    s0 = frame_tangent(n0, surface.dp_du)
    t0 = n0.cross(s0)
    local = vec3(0.0, 0.0, 1.0)
    if ti.static(has_height_maps):
        if model == HEIGHT_MAP:
            local = to_local(_height_normal(tex, slot, scale, surface, n0), s0, t0, n0)
    if model != HEIGHT_MAP:
        local = tex.unfiltered(slot, surface).xyz * 2.0 - 1.0
    side = 1.0 if wo.dot(n0) >= 0.0 else -1.0
    n_front = side * n0
    view = vec3(wo.dot(s0), wo.dot(t0), wo.dot(n_front))
    if view.z * view.dot(local) <= 0.0:  # the viewer behind the mapped normal: mirror it
        local = vec3(-local.x, -local.y, local.z)
    n = n_front
    if local.dot(local) > _TINY:
        local = ti.math.normalize(local)
        n = s0 * local.x + t0 * local.y + n_front * local.z
    tangent, _ = orthonormal_basis(n)
    along = s0 - n * n.dot(s0)  # Mitsuba's perturbed frame keeps s0 as near as it can
    if along.dot(along) > _TINY:
        tangent = ti.math.normalize(along)
    return n, tangent, n_front


@ti.func
def _tan2(cos_theta):
    c2 = cos_theta * cos_theta
    return ti.max(1.0 - c2, 0.0) / c2


@ti.func
def scattering_weight(n_front, n, wo, wi, one_sided):
    """The factor on f |cos| (and on a sample's weight) for light leaving along wi through the
    mapped normal n: zero where wi is on different sides of n_front and n, or where a one-sided
    material is seen from behind n; else Estevez et al.'s shadowing term for a bump of n's tilt."""
    weight = 0.0
    cos_i = wi.dot(n_front)
    if cos_i * wi.dot(n) > 0.0 and not (one_sided and wo.dot(n) <= 0.0):
        alpha2 = ti.min(0.125 * _tan2(n.dot(n_front)), 1.0)
        weight = 2.0 / (1.0 + ti.sqrt(1.0 + alpha2 * _tan2(cos_i)))
    return weight


@ti.func
def material_weight(mat, n, wo, wi, has_sidedness: ti.template()):
    """scattering_weight for a shaded Material (1 where no Mitsuba map tilted its normal n)."""
    weight = 1.0
    if mat.unmapped_normal.dot(mat.unmapped_normal) > 0.0:
        one_sided = False
        if ti.static(has_sidedness):
            one_sided = mat.sidedness == BACK_BLACK
        weight = scattering_weight(mat.unmapped_normal, n, wo, wi, one_sided)
    return weight

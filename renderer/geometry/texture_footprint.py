"""A pixel's footprint on a surface, in texture coordinates: what mip-mapped texture lookups filter
over (renderer/materials/texture_sampler.py, TextureTable.lookup).

Rays carry a cone (renderer/camera.py): `cone_width` metres wide where it meets the surface. The
cone cuts the surface's tangent plane in an ellipse whose axes are `width` across the ray and
`width / |cos|` along it (a grazing ray's footprint stretches along its direction). Each axis is
mapped to texture coordinates through the surface's dp/du, dp/dv by least squares (pbrt's
SurfaceInteraction::ComputeDifferentials does the same for ray differentials).

Cones go on from surface to surface with the path's length (Surface.cone_width), so after a
bounce a texture is read at about the footprint the camera's pixel would have at that distance
along the path; the camera narrows each pixel's cone as its samples accumulate (renderer/program.py,
footprint_shrink), so the filtering that smooths the first samples fades as the pixel converges.
"""
import taichi as ti

vec3 = ti.math.vec3

# The longest stretch a grazing ray gives the footprint along its direction (1 / |cos| beyond it
# reads the coarsest levels anyway).
MAX_STRETCH = 1e4


@ti.func
def uv_footprint(d, n, width, dp_du, dp_dv):
    """(du, dv) of the footprint's axis across the ray, then (du, dv) of the one along it, as one
    vec4: for a cone `width` wide meeting the surface of normal n (unit) along d (unit), with
    partial derivatives dp_du, dp_dv. Zero where there is no cone or the parametrisation is
    degenerate (lookups then read the image itself)."""
    out = ti.math.vec4(0.0)
    g11 = dp_du.dot(dp_du)
    g12 = dp_du.dot(dp_dv)
    g22 = dp_dv.dot(dp_dv)
    det = g11 * g22 - g12 * g12
    if width > 0.0 and det > 1e-12 * g11 * g22:
        across = n.cross(d)
        length = across.norm()
        if length < 1e-6:  # head-on: every direction in the plane is "across"
            across = dp_du / ti.sqrt(g11)
        else:
            across = across / length
        along = across.cross(n)
        cos = ti.abs(d.dot(n))
        a = across * width
        b = along * (width * ti.min(1.0 / ti.max(cos, 1e-30), MAX_STRETCH))
        inv = 1.0 / det
        ua, va = dp_du.dot(a), dp_dv.dot(a)
        ub, vb = dp_du.dot(b), dp_dv.dot(b)
        out = ti.math.vec4((g22 * ua - g12 * va) * inv, (g11 * va - g12 * ua) * inv,
                           (g22 * ub - g12 * vb) * inv, (g11 * vb - g12 * ub) * inv)
    return out


@ti.func
def footprint_shrink(sample_index):
    """How much a pixel's sample `sample_index` (0, 1, ...) narrows its cone: 1 / sqrt(index + 1),
    about the spacing of the pixel's samples so far (pbrt-v4 scales its footprints by
    1 / sqrt(spp) for the same reason). Sample 0 filters over the whole pixel; later ones over less,
    so the pixel's mean tends to the unfiltered image as samples accumulate."""
    return 1.0 / ti.sqrt(ti.cast(sample_index, ti.f32) + 1.0)

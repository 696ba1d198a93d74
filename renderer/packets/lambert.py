"""Lambert's lobe in lane arithmetic, as the scalar BSDF has it (materials/diffuse.py through
Bsdf.sample_at and eval_at): cosine-weighted about the shading normal on the viewer's side, and
nothing where the shading normal and the true surface disagree about which side a direction is
on (renderer/packets/shading_normals.py). The colour (albedo / pi times the cosine, or the albedo
as a sample's weight) is the caller's.
"""
import taichi as ti

from renderer.packets.lanes import cosine_hemisphere, mask
from renderer.packets.shading_normals import sides_agree
from renderer.sampling.warps import INV_PI


@ti.func
def lobe_normal(snx, sny, snz, cos_o):
    """The lobe's normal: the (consistent) shading normal on the viewer's side, which is the side
    of the geometric normal where cos_o = wo . n >= 0 (consistent_normals put it there)."""
    side = ti.select(cos_o >= 0.0, 1.0, -1.0)
    return side * snx, side * sny, side * snz


@ti.func
def sample(v1, v2, fx, fy, fz, snx, sny, snz, nx, ny, nz, ox, oy, oz):
    """Directions drawn from (v1, v2) about the lobe normal f: (x, y, z, density, valid mask).
    o: toward the viewer; n: the geometric normal."""
    bx, by, bz, cos_t = cosine_hemisphere(v1, v2, fx, fy, fz)
    valid = mask(cos_t > 0.0) & sides_agree(snx, sny, snz, nx, ny, nz, ox, oy, oz, bx, by, bz)
    return bx, by, bz, cos_t * INV_PI, valid


@ti.func
def toward(wx, wy, wz, fx, fy, fz, snx, sny, snz, nx, ny, nz, ox, oy, oz):
    """Toward the directions w: (cos theta to the lobe normal, the density sample would draw w
    with, mask of where the lobe reflects any light into o)."""
    cos_i = wx * fx + wy * fy + wz * fz
    usable = mask(cos_i > 0.0) & sides_agree(snx, sny, snz, nx, ny, nz, ox, oy, oz, wx, wy, wz)
    return cos_i, cos_i * INV_PI, usable

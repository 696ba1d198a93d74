"""Keeping shading normals consistent with the geometry they decorate."""
import taichi as ti

# Least cosine between the viewing direction and the shading normal on the viewer's side. Small
# enough to leave real shading detail alone, large enough to keep BSDF frames non-degenerate.
MIN_SHADING_COSINE = 1e-2


@ti.func
def consistent_shading_normal(ns, ng, wo):
    """Keep the interpolated normal on the geometric normal's side, and keep the viewer in front of
    it: where interpolation tilts ns away from wo (silhouettes of smooth low-poly meshes), bend it
    towards wo just enough. Without this, such hits shade black (seams) or sample directions
    below the true surface (light leaking through it)."""
    result = ns
    if result.dot(ng) < 0.0:
        result = -result
    side = 1.0 if wo.dot(ng) >= 0.0 else -1.0
    c = side * result.dot(wo)
    if c < MIN_SHADING_COSINE:
        result = ti.math.normalize(result + side * (MIN_SHADING_COSINE - c) * wo)
    return result

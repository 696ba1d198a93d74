"""The `diffuse_transmission` kind (pbrt-v4's diffusetransmission): Lambert reflection with
`base_color` on the side wo is on and Lambert transmission with `transmittance` on the other, a
thin sheet (a leaf, a blind, a lamp shade) that has no inside. A sample picks reflection or
transmission in proportion to the two colours' largest channels, as pbrt does. Local frame as in
renderer/materials/diffuse.py: z is the shading normal on wo's side."""
import taichi as ti

from renderer.materials.kinds import LobeFlags
from renderer.materials.lobes import BsdfSample
from renderer.sampling.warps import INV_PI, cosine_hemisphere

vec3 = ti.math.vec3


@ti.func
def _reflect_probability(mat):
    pr, pt = mat.base_color.max(), mat.transmittance.max()
    return pr / (pr + pt) if pr + pt > 0.0 else 0.0


@ti.func
def sample(bsdf, mat, n_f, t, b, entering, wo, u1, u2):
    pr = _reflect_probability(mat)
    wi = cosine_hemisphere(u2)
    colour, chosen = mat.base_color, pr
    if u1 >= pr:  # transmission: the mirror image of a cosine-distributed direction
        wi.z = -wi.z
        colour, chosen = mat.transmittance, 1.0 - pr
    pdf = chosen * ti.abs(wi.z) * INV_PI
    return BsdfSample(wi=wi, weight=colour / chosen if chosen > 0.0 else vec3(0.0), pdf=pdf, delta=0,
                      valid=1 if pdf > 0.0 else 0)


@ti.func
def evaluate(bsdf, mat, n_f, t, b, entering, wo, wi):
    pr = _reflect_probability(mat)
    colour, chosen = mat.base_color, pr
    if wi.z < 0.0:
        colour, chosen = mat.transmittance, 1.0 - pr
    cos = ti.abs(wi.z) * INV_PI
    return colour * cos, chosen * cos


@ti.func
def flags(bsdf, mat):
    return LobeFlags.REFLECTION | LobeFlags.TRANSMISSION | LobeFlags.DIFFUSE

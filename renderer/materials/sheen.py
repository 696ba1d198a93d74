"""The sheen layer of the principled model (glTF KHR_materials_sheen): the soft, back-lit glow of
velvet, cloth and dust, as fibres standing on the surface scatter light near grazing angles.

Microfacet form with the "Charlie" distribution of Estevez and Kulla 2017 ('Production friendly
microfacet sheen BRDF') and the visibility term of Neubelt and Pettineo 2013 that glTF's reference
uses, in the local frame (z = normal, both directions above):

    D(h) = (2 + 1 / a) sin(theta_h)^(1 / a) / (2 pi),   a = roughness^2 (roughness >= MIN_ROUGHNESS)
    f(wo, wi) = sheen_color D(h) / (4 (mu_i + mu_o - mu_i mu_o))

Layering (glTF's albedo scaling): the layer below is weighted by 1 - max(sheen_color) E(mu_o),
where E is the sheen lobe's directional albedo for a white colour (tabulated by
scripts/make_sheen_albedo_table.py), so a white sheen over a white base returns exactly 1 (up to
the table's error). The lobe is sampled by the cosine.
"""
from pathlib import Path

import numpy as np
import taichi as ti

from renderer.sampling.warps import INV_PI, PI
from renderer.runtime.upload import upload_fields

TABLE_FILE = Path(__file__).resolve().parent / "data" / "sheen_albedo.npz"
# Below this roughness the distribution is a sliver at exactly grazing half vectors that f32 cannot
# resolve (sin^(1/a) underflows); glTF viewers clamp at the same place.
MIN_ROUGHNESS = 0.07


def load_table() -> dict:
    """E [roughness node, sqrt(mu) node]: roughness nodes uniform on [MIN_ROUGHNESS, 1]."""
    try:
        data = np.load(TABLE_FILE)
    except OSError as error:
        raise RuntimeError(f"{TABLE_FILE}: cannot read the sheen albedo table ({error}); "
                           "run scripts/make_sheen_albedo_table.py") from None
    return {"albedo": data["albedo"].astype(np.float64)}


def charlie_np(cos_h, roughness):
    """D(h) in numpy (float64), for the table and the tests."""
    a = np.maximum(roughness, MIN_ROUGHNESS) ** 2
    sin2 = np.clip(1.0 - cos_h * cos_h, 0.0, 1.0)
    return (2.0 + 1.0 / a) * sin2 ** (0.5 / a) / (2.0 * np.pi)


def visibility_np(mu_o, mu_i):
    return 1.0 / (4.0 * (mu_i + mu_o - mu_i * mu_o))


def albedo_lookup(table: dict, mu, roughness):
    """numpy twin of SheenAlbedo.albedo (bilinear in sqrt(mu) and roughness)."""
    e = table["albedo"]
    nr, nm = e.shape
    y = (np.clip(roughness, MIN_ROUGHNESS, 1.0) - MIN_ROUGHNESS) / (1.0 - MIN_ROUGHNESS) * (nr - 1)
    x = np.sqrt(np.clip(mu, 0.0, 1.0)) * (nm - 1)
    i = np.minimum(np.asarray(y).astype(int), nr - 2)
    j = np.minimum(np.asarray(x).astype(int), nm - 2)
    fy, fx = y - i, x - j
    top = e[i, j] * (1 - fx) + e[i, j + 1] * fx
    bottom = e[i + 1, j] * (1 - fx) + e[i + 1, j + 1] * fx
    return top * (1 - fy) + bottom * fy


@ti.func
def charlie(cos_h, roughness):
    a = ti.max(roughness, MIN_ROUGHNESS)
    a = a * a
    sin2 = ti.max(1.0 - cos_h * cos_h, 0.0)
    return (2.0 + 1.0 / a) * ti.pow(sin2, 0.5 / a) / (2.0 * PI)


@ti.func
def sheen_eval(color, roughness, wo, wi):
    """(f |cos wi|, cosine pdf) of the sheen lobe; zero below the surface."""
    value = ti.math.vec3(0.0)
    pdf = 0.0
    if wi.z > 0.0 and wo.z > 0.0:
        h = ti.math.normalize(wo + wi)
        v = 1.0 / (4.0 * (wi.z + wo.z - wi.z * wo.z))
        value = color * (charlie(h.z, roughness) * v * wi.z)
        pdf = wi.z * INV_PI
    return value, pdf


@ti.data_oriented
class SheenAlbedo:
    """E(mu, roughness) of a white sheen lobe on the device (32 x 32 floats)."""

    def __init__(self):
        table = load_table()["albedo"]
        self.nr, self.nm = table.shape
        self.field = ti.field(ti.f32, shape=table.shape)
        upload_fields([(self.field, table)])

    @ti.func
    def albedo(self, mu, roughness):
        y = (ti.math.clamp(roughness, MIN_ROUGHNESS, 1.0) - MIN_ROUGHNESS) / (1.0 - MIN_ROUGHNESS) * (self.nr - 1)
        x = ti.sqrt(ti.math.clamp(mu, 0.0, 1.0)) * (self.nm - 1)
        i = ti.min(ti.cast(y, ti.i32), self.nr - 2)
        j = ti.min(ti.cast(x, ti.i32), self.nm - 2)
        fy = y - i
        fx = x - j
        top = self.field[i, j] * (1.0 - fx) + self.field[i, j + 1] * fx
        bottom = self.field[i + 1, j] * (1.0 - fx) + self.field[i + 1, j + 1] * fx
        return top * (1.0 - fy) + bottom * fy

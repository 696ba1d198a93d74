"""Multiple-scattering energy compensation for GGX reflection (Kulla and Conty 2017, 'Revisiting
physically based shading at Imageworks').

A single-scattering microfacet model drops the light that bounces more than once between
microfacets: a white GGX mirror of roughness 1 returns only 31% at normal incidence. The lost
energy comes back as a second, diffuse-like lobe

    f_ms(wo, wi) = F_ms (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)),

where E(mu) is the directional albedo of the lobe with Fresnel 1 (tabulated by
scripts/make_ggx_albedo_table.py), E_avg = 2 int E(mu) mu dmu its cosine-weighted mean, and

    F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg))

the colour of light that leaves after several bounces, each tinted by the mean Fresnel F_avg.
With F = 1 the lobe returns exactly what single scattering lost, E(mu_o) + (1 - E(mu_o)) = 1; it
is symmetric in wo and wi, so reciprocity holds. The lobe is sampled by the cosine, chosen with
probability 1 - E(mu_o): its share of the energy when F = 1.
"""
from pathlib import Path

import numpy as np
import taichi as ti

from renderer.sampling.warps import INV_PI
from renderer.runtime.upload import upload_fields

TABLE_FILE = Path(__file__).resolve().parent / "data" / "ggx_albedo.npz"
# 1 - E_avg is about 1e-4 at the smallest roughness: the floor only keeps the division finite
# where the lobe's numerator is (nearly) zero too.
MIN_LOSS = 1e-6


def load_table() -> dict:
    """The tabulated albedo [sqrt(roughness), sqrt(mu)] (nodes uniform in both square roots) and
    its cosine-weighted average per roughness node."""
    try:
        data = np.load(TABLE_FILE)
    except OSError as error:
        raise RuntimeError(f"{TABLE_FILE}: cannot read the GGX albedo table ({error}); "
                           "run scripts/make_ggx_albedo_table.py") from None
    albedo = data["albedo"].astype(np.float64)
    return {"albedo": albedo, "average": cosine_average(albedo)}


def cosine_average(albedo: np.ndarray) -> np.ndarray:
    """E_avg = 2 int_0^1 E(mu) mu dmu = 4 int_0^1 E(x^2) x^3 dx over the last axis (nodes uniform in
    x = sqrt(mu)), for E linear in x between nodes, as the lookups interpolate it: Gauss-Legendre
    with 3 points per segment is exact for that degree-4 integrand, so E_avg agrees with the lookup
    to rounding."""
    size = albedo.shape[-1]
    nodes, weights = np.polynomial.legendre.leggauss(3)
    h = 1.0 / (size - 1)
    total = np.zeros(albedo.shape[:-1])
    for j in range(size - 1):
        x = j * h + 0.5 * h * (nodes + 1.0)
        t = (x - j * h) / h
        e = albedo[..., j, None] * (1.0 - t) + albedo[..., j + 1, None] * t
        total += 0.5 * h * np.sum(weights * e * 4.0 * x ** 3, axis=-1)
    return total


def albedo_lookup(table: dict, mu, roughness):
    """numpy twin of GgxAlbedo.albedo (bilinear in sqrt(mu) and sqrt(roughness))."""
    albedo = table["albedo"]
    size = albedo.shape[0]
    x = np.sqrt(np.clip(mu, 0.0, 1.0)) * (size - 1)
    y = np.sqrt(np.clip(roughness, 0.0, 1.0)) * (size - 1)
    j = np.minimum(x.astype(int), size - 2)
    i = np.minimum(y.astype(int), size - 2)
    fx, fy = x - j, y - i
    top = albedo[i, j] * (1 - fx) + albedo[i, j + 1] * fx
    bottom = albedo[i + 1, j] * (1 - fx) + albedo[i + 1, j + 1] * fx
    return top * (1 - fy) + bottom * fy


def average_lookup(table: dict, roughness):
    average = table["average"]
    y = np.sqrt(np.clip(roughness, 0.0, 1.0)) * (len(average) - 1)
    i = np.minimum(y.astype(int), len(average) - 2)
    f = y - i
    return average[i] * (1 - f) + average[i + 1] * f


@ti.data_oriented
class GgxAlbedo:
    """E(mu, roughness) and E_avg(roughness) on the device (a 32 x 32 table: 4 KiB)."""

    def __init__(self):
        table = load_table()
        self.size = table["albedo"].shape[0]
        self.albedo_field = ti.field(ti.f32, shape=table["albedo"].shape)
        self.average_field = ti.field(ti.f32, shape=self.size)
        upload_fields([(self.albedo_field, table["albedo"]), (self.average_field, table["average"])])

    @ti.func
    def albedo(self, mu, roughness):
        n = self.size
        x = ti.sqrt(ti.math.clamp(mu, 0.0, 1.0)) * (n - 1)
        y = ti.sqrt(ti.math.clamp(roughness, 0.0, 1.0)) * (n - 1)
        j = ti.min(ti.cast(x, ti.i32), n - 2)
        i = ti.min(ti.cast(y, ti.i32), n - 2)
        fx = x - j
        fy = y - i
        top = self.albedo_field[i, j] * (1.0 - fx) + self.albedo_field[i, j + 1] * fx
        bottom = self.albedo_field[i + 1, j] * (1.0 - fx) + self.albedo_field[i + 1, j + 1] * fx
        return top * (1.0 - fy) + bottom * fy

    @ti.func
    def average(self, roughness):
        y = ti.sqrt(ti.math.clamp(roughness, 0.0, 1.0)) * (self.size - 1)
        i = ti.min(ti.cast(y, ti.i32), self.size - 2)
        f = y - i
        return self.average_field[i] * (1.0 - f) + self.average_field[i + 1] * f

    @ti.func
    def multiple_scattering(self, f_avg, alpha, wo, wi):
        """(f_ms |cos wi|, its cosine-sampling pdf, sampling_share) in the local frame (wo.z > 0);
        f_avg: vec3. The share comes along because it needs the same lookup of E(mu_o)."""
        roughness = ti.sqrt(alpha)
        loss_o = ti.math.clamp(1.0 - self.albedo(wo.z, roughness), 0.0, 1.0)
        value = ti.math.vec3(0.0)
        pdf = 0.0
        if wi.z > 0.0:
            e_avg = self.average(roughness)
            f_ms = f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg))
            loss_i = 1.0 - self.albedo(wi.z, roughness)
            value = f_ms * (loss_o * loss_i / ti.max(1.0 - e_avg, MIN_LOSS) * INV_PI * wi.z)
            pdf = wi.z * INV_PI
        return value, pdf, loss_o

    @ti.func
    def sampling_share(self, alpha, wo):
        """Probability of sampling the multiple-scattering lobe: its energy share when F = 1."""
        return ti.math.clamp(1.0 - self.albedo(wo.z, ti.sqrt(alpha)), 0.0, 1.0)

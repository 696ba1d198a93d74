"""Multiple-scattering compensation of rough dielectric interfaces (glass), after Kulla and Conty
2017 ('Revisiting physically based shading at Imageworks', the dielectric part).

A single-scattering microfacet interface drops the light that meets more than one microfacet: a
white glass ball of roughness 0.5 in a white furnace comes out at 0.82 on average, 0.54 at its rim,
and at roughness 1 at 0.36. Light must not vanish at a non-absorbing interface, so the lost energy
comes back as a diffuse-like lobe on both sides. Per side s of wo (o: outside, eta = ior; i: inside,
eta = 1 / ior), with E_s(mu) = R_s(mu) + T_s(mu) the energy the single-scattering interface returns
(tabulated by scripts/make_dielectric_albedo_table.py) and Eavg_s its cosine-weighted mean:

    reflection    f = (1 - x_s) (1 - E_s(mu_o)) (1 - E_s(mu_i)) / (pi (1 - Eavg_s))
    transmission  f = x_s (1 - E_s(mu_o)) (1 - E_s'(mu_i)) / (eta_s^2 pi (1 - Eavg_s'))

where s' is the other side and x_s the share of the lost energy that crosses the interface. From
side s the lobe returns exactly 1 - E_s(mu_o) in energy units (transmitted radiance carries
1 / eta^2, as in the single-scattering lobe), so E_s + (1 - E_s) = 1: the interface neither creates
nor destroys light. Generalised reciprocity, f_T(o->i) / n_i^2 = f_T(i->o) / n_o^2, ties the two
shares: x_o (1 - Eavg_o) = ior^2 x_i (1 - Eavg_i). x_o is the single-scattering transmitted share
Tavg_o / Eavg_o; where that would make x_i exceed 1, x_i = 1 and x_o follows.

Exactness holds for the *interpolated* tables: Eavg is the integral of the interpolated E
(energy.cosine_average), and the lookups below interpolate linearly in sqrt(mu), sqrt(roughness)
and x = (ior - 1) / (ior + 1), the table's node spacings; averages are linear in the tables, so
they interpolate the same way. What remains is E_table - E_true, tested in tests/materials.

The lobe is chosen with probability 1 - E_s(mu_o) (its energy share for a white interface) and
sampled by the cosine; the result is weighted by the whole BSDF over the mixture pdf, so `sample`
and `eval` agree. The reflection table of side o also serves the energy-conserving layering of the
principled model (a dielectric coat over a base: `reflectance`).
"""
from pathlib import Path

import numpy as np
import taichi as ti

from renderer.materials import lobes
from renderer.materials.energy import cosine_average
from renderer.materials.lobes import BsdfSample
from renderer.sampling.warps import INV_PI, cosine_hemisphere
from renderer.runtime.upload import upload_fields

vec3 = ti.math.vec3
TABLE_FILE = Path(__file__).resolve().parent / "data" / "dielectric_albedo.npz"
# Where 1 - Eavg is (nearly) zero, so is the numerator of the lobe: the floor only keeps it finite.
MIN_LOSS = 1e-6
OUTSIDE, INSIDE = 0, 1


def load_table() -> dict:
    """Tables [side, sqrt(roughness), x, sqrt(mu)] and their cosine averages [side, roughness, x]."""
    try:
        data = np.load(TABLE_FILE)
    except OSError as error:
        raise RuntimeError(f"{TABLE_FILE}: cannot read the dielectric albedo table ({error}); "
                           "run scripts/make_dielectric_albedo_table.py") from None
    reflect = data["reflect"].astype(np.float64)
    transmit = data["transmit"].astype(np.float64)
    albedo = reflect + transmit
    average = cosine_average(albedo)
    transmit_average = cosine_average(transmit)
    share = np.where(average > 0.0, transmit_average / np.maximum(average, 1e-12), 0.0)
    return {"reflect": reflect, "albedo": albedo, "average": average, "reflect_average": cosine_average(reflect),
            "transmit_share": share[OUTSIDE], "x_max": float(data["x"][-1])}


def ior_coordinate(ior):
    """x = (ior - 1) / (ior + 1): the square root of the interface's reflectance at normal incidence."""
    return (ior - 1.0) / (ior + 1.0)


# --- numpy twins of the device lookups (for tests and host-side figures) -------------------------
def _weights_np(value, size, top=1.0):
    t = np.clip(np.asarray(value, np.float64) / top, 0.0, 1.0) * (size - 1)
    i = np.minimum(t.astype(int), size - 2)
    return i, t - i


def albedo_lookup(table: dict, name: str, side: int, mu, roughness, ior):
    """Trilinear lookup of table[name] (reflect or albedo) as the device does it."""
    a = table[name][side]
    i, fi = _weights_np(np.sqrt(roughness), a.shape[0])
    k, fk = _weights_np(ior_coordinate(np.asarray(ior, np.float64)), a.shape[1], table["x_max"])
    j, fj = _weights_np(np.sqrt(np.clip(mu, 0.0, 1.0)), a.shape[2])
    total = 0.0
    for di, wi in ((0, 1 - fi), (1, fi)):
        for dk, wk in ((0, 1 - fk), (1, fk)):
            for dj, wj in ((0, 1 - fj), (1, fj)):
                total = total + wi * wk * wj * a[i + di, k + dk, j + dj]
    return total


def average_lookup(table: dict, name: str, roughness, ior, side: int | None = None):
    a = table[name] if side is None else table[name][side]
    i, fi = _weights_np(np.sqrt(roughness), a.shape[0])
    k, fk = _weights_np(ior_coordinate(np.asarray(ior, np.float64)), a.shape[1], table["x_max"])
    return ((1 - fi) * ((1 - fk) * a[i, k] + fk * a[i, k + 1]) + fi * ((1 - fk) * a[i + 1, k] + fk * a[i + 1, k + 1]))


@ti.data_oriented
class DielectricAlbedo:
    """The tables on the device (2 x 32 x 16 x 32 albedos, 128 KiB) and the compensated lobe."""

    def __init__(self):
        table = load_table()
        sides, nr, nx, nmu = table["albedo"].shape
        self.nr, self.nx, self.nmu = nr, nx, nmu
        self.x_max = table["x_max"]
        self.albedo_field = ti.field(ti.f32, shape=(sides, nr, nx, nmu))
        self.reflect_field = ti.field(ti.f32, shape=(nr, nx, nmu))  # side o only: the coat's
        # Per (roughness, x): Eavg_o, Eavg_i, the transmitted share x_o, Ravg_o.
        self.averages = ti.Vector.field(4, ti.f32, shape=(nr, nx))
        averages = np.stack([table["average"][OUTSIDE], table["average"][INSIDE], table["transmit_share"],
                             table["reflect_average"][OUTSIDE]], axis=-1)
        upload_fields([(self.albedo_field, table["albedo"]), (self.reflect_field, table["reflect"][OUTSIDE]),
                       (self.averages, averages)])

    # --- lookups ------------------------------------------------------------------------------
    @ti.func
    def _coords(self, roughness, ior):
        r = ti.sqrt(ti.math.clamp(roughness, 0.0, 1.0)) * (self.nr - 1)
        x = ti.math.clamp((ior - 1.0) / (ior + 1.0) / self.x_max, 0.0, 1.0) * (self.nx - 1)
        i = ti.min(ti.cast(r, ti.i32), self.nr - 2)
        k = ti.min(ti.cast(x, ti.i32), self.nx - 2)
        return i, r - i, k, x - k

    @ti.func
    def _mu_coord(self, mu):
        m = ti.sqrt(ti.math.clamp(mu, 0.0, 1.0)) * (self.nmu - 1)
        j = ti.min(ti.cast(m, ti.i32), self.nmu - 2)
        return j, m - j

    @ti.func
    def albedo(self, side, mu, roughness, ior):
        """E_side(mu): energy the single-scattering interface reflects plus transmits."""
        i, fi, k, fk = self._coords(roughness, ior)
        j, fj = self._mu_coord(mu)
        total = 0.0
        for di, dk, dj in ti.static(ti.ndrange(2, 2, 2)):
            w = _lerp_weight(fi, di) * _lerp_weight(fk, dk) * _lerp_weight(fj, dj)
            total += w * self.albedo_field[side, i + di, k + dk, j + dj]
        return total

    @ti.func
    def _averages(self, roughness, ior):
        i, fi, k, fk = self._coords(roughness, ior)
        return ((1.0 - fi) * ((1.0 - fk) * self.averages[i, k] + fk * self.averages[i, k + 1])
                + fi * ((1.0 - fk) * self.averages[i + 1, k] + fk * self.averages[i + 1, k + 1]))

    @ti.func
    def reflectance(self, mu, roughness, ior):
        """(R_o(mu), Ravg_o): what a rough dielectric coat reflects from outside, single scattering,
        and its cosine average; the rest reaches the layer below (principled layering)."""
        i, fi, k, fk = self._coords(roughness, ior)
        j, fj = self._mu_coord(mu)
        total = 0.0
        for di, dk, dj in ti.static(ti.ndrange(2, 2, 2)):
            w = _lerp_weight(fi, di) * _lerp_weight(fk, dk) * _lerp_weight(fj, dj)
            total += w * self.reflect_field[i + di, k + dk, j + dj]
        return total, self._averages(roughness, ior).w

    @ti.func
    def smooth_reflectance_average(self, ior):
        """The cosine-weighted mean Fresnel reflectance of a smooth interface seen from outside."""
        return self._averages(0.0, ior).w

    # --- the multiple-scattering lobe -------------------------------------------------------------
    @ti.func
    def _shares(self, roughness, ior, side):
        """(x_s, 1 - Eavg_s, 1 - Eavg_s') for wo on `side`: the reciprocity-tied transmitted shares."""
        avg = self._averages(roughness, ior)
        loss_o = ti.max(1.0 - avg.x, MIN_LOSS)
        loss_i = ti.max(1.0 - avg.y, MIN_LOSS)
        x_o = ti.math.clamp(avg.z, 0.0, 1.0)
        x_i = x_o * loss_o / (ior * ior * loss_i)
        if x_i > 1.0:
            x_i = 1.0
            x_o = ior * ior * loss_i / loss_o
        share, loss_s, loss_other = x_o, loss_o, loss_i
        if side == INSIDE:
            share, loss_s, loss_other = x_i, loss_i, loss_o
        return share, loss_s, loss_other

    @ti.func
    def _ms_eval(self, tint, roughness, ior, side, eta, wo, wi):
        """(f_ms |cos wi|, its sampling pdf, its sampling probability 1 - E_s(mu_o))."""
        share, loss_s, loss_other = self._shares(roughness, ior, side)
        lost_o = ti.math.clamp(1.0 - self.albedo(side, wo.z, roughness, ior), 0.0, 1.0)
        value = vec3(0.0)
        pdf = 0.0
        cos_i = ti.abs(wi.z)
        if wi.z > 0.0:
            lost_i = ti.math.clamp(1.0 - self.albedo(side, cos_i, roughness, ior), 0.0, 1.0)
            value = vec3((1.0 - share) * lost_o * lost_i / loss_s * INV_PI * cos_i)
            pdf = (1.0 - share) * cos_i * INV_PI
        elif wi.z < 0.0:
            lost_i = ti.math.clamp(1.0 - self.albedo(1 - side, cos_i, roughness, ior), 0.0, 1.0)
            value = tint * (share * lost_o * lost_i / (eta * eta * loss_other) * INV_PI * cos_i)
            pdf = share * cos_i * INV_PI
        return value, pdf, lost_o

    @ti.func
    def eval(self, tint, alpha, eta, wo, wi):
        """The compensated rough interface: (f |cos wi|, pdf) of `sample`; wo.z > 0, alpha > 0."""
        side, ior, roughness = _side_of(eta, alpha)
        v_ss, pdf_ss = lobes.dielectric_eval(tint, alpha, eta, wo, wi)
        v_ms, pdf_ms, p_ms = self._ms_eval(tint, roughness, ior, side, eta, wo, wi)
        return v_ss + v_ms, (1.0 - p_ms) * pdf_ss + p_ms * pdf_ms

    @ti.func
    def direction(self, tint, alpha, eta, wo, u1, u2):
        """A direction from the mixture of the single-scattering lobe and the compensation lobe
        (valid = 0 where the single-scattering sampler fails)."""
        side, ior, roughness = _side_of(eta, alpha)
        share, _, _ = self._shares(roughness, ior, side)
        p_ms = ti.math.clamp(1.0 - self.albedo(side, wo.z, roughness, ior), 0.0, 1.0)
        wi = vec3(0.0, 0.0, 1.0)
        valid = 1
        if u1 < p_ms:
            wi = cosine_hemisphere(u2)
            if u1 / p_ms < share:
                wi.z = -wi.z
            valid = 1 if wi.z != 0.0 else 0
        else:
            s = lobes.dielectric_sample(tint, alpha, eta, wo, (u1 - p_ms) / (1.0 - p_ms), u2)
            wi = s.wi
            valid = s.valid
        return wi, valid

    @ti.func
    def sample(self, tint, alpha, eta, wo, u1, u2):
        wi, valid = self.direction(tint, alpha, eta, wo, u1, u2)
        s = lobes.invalid_sample()
        if valid == 1:
            value, pdf = self.eval(tint, alpha, eta, wo, wi)
            if pdf > 0.0:
                s = BsdfSample(wi=wi, weight=value / pdf, pdf=pdf, delta=0, valid=1)
        return s


@ti.func
def _lerp_weight(f, upper: ti.template()):
    """The linear-interpolation weight of the lower (upper = 0) or upper (1) node."""
    return f if ti.static(upper == 1) else 1.0 - f


@ti.func
def _side_of(eta, alpha):
    """(side, ior, roughness) of an interface seen with relative index eta = n_far / n_near."""
    side = OUTSIDE
    ior = eta
    if eta < 1.0:
        side = INSIDE
        ior = 1.0 / eta
    return side, ior, ti.sqrt(alpha)

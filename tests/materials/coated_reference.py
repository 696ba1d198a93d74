"""A numpy (float64, scalar) transcription of pbrt-v4's LayeredBxDF::f and ::PDF with a dielectric top
and a diffuse or conductor base, as renderer/materials/coated.py computes them: written from pbrt's
definitions (bxdfs.h, bxdfs.cpp, scattering.h), with the random numbers drawn from the same hash
of wo and wi (renderer/sampling/rng.py's pcg_hash and uniform, walk_key's order), so that the two
follow the same walks and agree to rounding."""
import math

import numpy as np

from renderer.materials.conductor_ior import fresnel_conductor_np

M32 = 0xFFFFFFFF
INV_PI = 1.0 / math.pi
SMOOTH_ALPHA = 1e-3
FLT_MIN = 1.1754944e-38
REFLECT, TRANSMIT, ALL = 1, 2, 3


def pcg_hash(v):
    state = (v * 747796405 + 2891336453) & M32
    word = (((state >> ((state >> 28) + 4)) ^ state) * 277803737) & M32
    return ((word >> 22) ^ word) & M32


def walk_key(a, b):
    k = 0x2545F491
    for x in (*a, *b):
        k = pcg_hash(k ^ int(np.float32(x).view(np.uint32)))
    return k


class Rng:
    def __init__(self, key):
        self.key, self.dim = key, 0

    def __call__(self):
        h = pcg_hash(self.key ^ pcg_hash((self.dim + 0x68E31DA4) & M32))
        self.dim += 1
        return (h >> 8) / 16777216.0


def _norm(v):
    return v / np.linalg.norm(v)


def ggx_d(m, ax, ay):
    t = m[0] ** 2 / ax ** 2 + m[1] ** 2 / ay ** 2 + m[2] ** 2
    return 1.0 / (math.pi * ax * ay * t * t)


def lam(w, ax, ay):
    return 0.5 * (math.sqrt(1.0 + (ax ** 2 * w[0] ** 2 + ay ** 2 * w[1] ** 2) / max(w[2] ** 2, 1e-20)) - 1.0)


def g1(w, ax, ay):
    return 1.0 / (1.0 + lam(w, ax, ay))


def g2(wo, wi, ax, ay):
    return 1.0 / (1.0 + lam(wo, ax, ay) + lam(wi, ax, ay))


def tr_pdf(w, m, ax, ay):
    return g1(w, ax, ay) / abs(w[2]) * ggx_d(m, ax, ay) * abs(w @ m)


def visible_normal(w, ax, ay, u):
    """Heitz 2018 (microfacet.sample_visible_normal) of w, or of -w below."""
    v = w if w[2] >= 0.0 else -w
    vh = _norm(np.array([ax * v[0], ay * v[1], v[2]]))
    lensq = vh[0] ** 2 + vh[1] ** 2
    t1 = np.array([-vh[1], vh[0], 0.0]) / math.sqrt(lensq) if lensq > 0.0 else np.array([1.0, 0.0, 0.0])
    t2 = np.cross(vh, t1)
    r, phi = math.sqrt(u[0]), 2.0 * math.pi * u[1]
    p1, p2 = r * math.cos(phi), r * math.sin(phi)
    s = 0.5 * (1.0 + vh[2])
    p2 = (1.0 - s) * math.sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2
    nh = p1 * t1 + p2 * t2 + math.sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh
    return _norm(np.array([ax * nh[0], ay * nh[1], max(1e-6, nh[2])]))


def cosine_hemisphere(u):
    a = 2.0 * np.asarray(u) - 1.0
    r = phi = 0.0
    if a[0] != 0.0 or a[1] != 0.0:
        if abs(a[0]) > abs(a[1]):
            r, phi = a[0], math.pi / 4.0 * (a[1] / a[0])
        else:
            r, phi = a[1], math.pi / 2.0 - math.pi / 4.0 * (a[0] / a[1])
    d = np.array([r * math.cos(phi), r * math.sin(phi)])
    return np.array([d[0], d[1], math.sqrt(max(0.0, 1.0 - d @ d))])


def fr_dielectric(c, eta):
    c = min(max(c, -1.0), 1.0)
    if c < 0.0:
        eta, c = 1.0 / eta, -c
    s2t = (1.0 - c * c) / (eta * eta)
    if s2t >= 1.0:
        return 1.0
    ct = math.sqrt(1.0 - s2t)
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return 0.5 * (rs * rs + rp * rp)


def refract(wi, n, eta):
    c = n @ wi
    if c < 0.0:
        eta, c, n = 1.0 / eta, -c, -n
    s2t = max(0.0, 1.0 - c * c) / (eta * eta)
    if s2t >= 1.0:
        return None, eta
    ct = math.sqrt(1.0 - s2t)
    return -wi / eta + (c / eta - ct) * n, eta


def reflect(wo, m):
    return 2.0 * (wo @ m) * m - wo


def power(f, g):
    return f * f / (f * f + g * g) if f * f + g * g > 0.0 else 0.0


class Layered:
    """p: tests/materials/coated_kernels.params_row's dict."""

    def __init__(self, p):
        self.p = {k: (np.asarray(v, np.float64) if isinstance(v, tuple) else v) for k, v in p.items()}
        q = self.p
        self.top_smooth = q["eta"] == 1.0 or max(q["alpha_x"], q["alpha_y"]) < SMOOTH_ALPHA
        self.base_smooth = q["base"] == 1 and q["c_alpha"] < SMOOTH_ALPHA

    # (f vec3, wi, pdf, reflection, specular) or None
    def top_sample(self, wo, uc, u, radiance, flags):
        q = self.p
        ax, ay = q["alpha_x"], q["alpha_y"]
        smooth = self.top_smooth
        if not smooth and wo[2] == 0.0:
            return None
        m = np.array([0.0, 0.0, 1.0]) if smooth else visible_normal(wo, ax, ay, u)
        r = fr_dielectric(wo @ m, q["eta"])
        pr = r if flags & REFLECT else 0.0
        pt = 1.0 - r if flags & TRANSMIT else 0.0
        if pr + pt <= 0.0:
            return None
        if uc < pr / (pr + pt):
            wi = reflect(wo, m)
            if smooth:
                return np.full(3, r / abs(wi[2])), wi, pr / (pr + pt), True, True
            if wi[2] * wo[2] <= 0.0:
                return None
            pdf = tr_pdf(wo, m, ax, ay) / (4.0 * abs(wo @ m)) * pr / (pr + pt)
            f = ggx_d(m, ax, ay) * g2(wo, wi, ax, ay) * r / (4.0 * wi[2] * wo[2])
            return np.full(3, f), wi, pdf, True, False
        wi, etap = refract(wo, m, q["eta"])
        if wi is None or wi[2] * wo[2] >= 0.0 or wi[2] == 0.0:
            return None
        ft, pdf = (1.0 - r) / abs(wi[2]), pt / (pr + pt)
        if not smooth:
            denom = (wi @ m + (wo @ m) / etap) ** 2
            pdf *= tr_pdf(wo, m, ax, ay) * abs(wi @ m) / denom
            ft = (1.0 - r) * ggx_d(m, ax, ay) * g2(wo, wi, ax, ay) * abs((wi @ m) * (wo @ m) / (wi[2] * wo[2] * denom))
        if radiance:
            ft /= etap * etap
        return np.full(3, ft), wi, pdf, False, smooth

    def _half(self, wo, wi):
        reflect_ = wi[2] * wo[2] > 0.0
        etap = 1.0 if reflect_ else (self.p["eta"] if wo[2] > 0.0 else 1.0 / self.p["eta"])
        m = wi * etap + wo
        if wi[2] == 0.0 or wo[2] == 0.0 or m @ m == 0.0:
            return None
        m = _norm(m)
        if m[2] < 0.0:
            m = -m
        if (m @ wi) * wi[2] < 0.0 or (m @ wo) * wo[2] < 0.0:
            return None
        return m, etap, reflect_

    def top_f(self, wo, wi, radiance):
        q = self.p
        if self.top_smooth or (h := self._half(wo, wi)) is None:
            return np.zeros(3)
        m, etap, reflect_ = h
        ax, ay = q["alpha_x"], q["alpha_y"]
        r = fr_dielectric(wo @ m, q["eta"])
        if reflect_:
            return np.full(3, ggx_d(m, ax, ay) * g2(wo, wi, ax, ay) * r / abs(4.0 * wi[2] * wo[2]))
        denom = (wi @ m + (wo @ m) / etap) ** 2 * wi[2] * wo[2]
        f = ggx_d(m, ax, ay) * (1.0 - r) * g2(wo, wi, ax, ay) * abs((wi @ m) * (wo @ m) / denom)
        return np.full(3, f / (etap * etap) if radiance else f)

    def top_pdf(self, wo, wi, flags):
        q = self.p
        if self.top_smooth or (h := self._half(wo, wi)) is None:
            return 0.0
        m, etap, reflect_ = h
        ax, ay = q["alpha_x"], q["alpha_y"]
        r = fr_dielectric(wo @ m, q["eta"])
        pr = r if flags & REFLECT else 0.0
        pt = 1.0 - r if flags & TRANSMIT else 0.0
        if pr + pt <= 0.0:
            return 0.0
        if reflect_:
            return tr_pdf(wo, m, ax, ay) / (4.0 * abs(wo @ m)) * pr / (pr + pt)
        denom = (wi @ m + (wo @ m) / etap) ** 2
        return tr_pdf(wo, m, ax, ay) * abs(wi @ m) / denom * pt / (pr + pt)

    def _conductor(self, wo, wi, m):
        a = self.p["c_alpha"]
        fr = fresnel_conductor_np(np.array([abs(wo @ m)]), self.p["c_eta"], self.p["c_k"])[0]
        return ggx_d(m, a, a) * fr * g2(wo, wi, a, a) / (4.0 * abs(wi[2]) * abs(wo[2]))

    def base_sample(self, wo, uc, u, flags):
        q = self.p
        if not flags & REFLECT:
            return None
        if q["base"] == 0:
            wi = cosine_hemisphere(u)
            if wo[2] < 0.0:
                wi[2] = -wi[2]
            return q["reflectance"] * INV_PI, wi, abs(wi[2]) * INV_PI, True, False
        if self.base_smooth:
            wi = np.array([-wo[0], -wo[1], wo[2]])
            c = abs(wi[2])
            return fresnel_conductor_np(np.array([c]), q["c_eta"], q["c_k"])[0] / c, wi, 1.0, True, True
        if wo[2] == 0.0:
            return None
        a = q["c_alpha"]
        m = visible_normal(wo, a, a, u)
        wi = reflect(wo, m)
        if wi[2] * wo[2] <= 0.0:
            return None
        return self._conductor(wo, wi, m), wi, tr_pdf(wo, m, a, a) / (4.0 * abs(wo @ m)), True, False

    def base_f(self, wo, wi):
        q = self.p
        if wo[2] * wi[2] <= 0.0:
            return np.zeros(3)
        if q["base"] == 0:
            return q["reflectance"] * INV_PI
        if self.base_smooth:
            return np.zeros(3)
        return self._conductor(wo, wi, _norm(wi + wo))

    def base_pdf(self, wo, wi):
        q = self.p
        if wo[2] * wi[2] <= 0.0:
            return 0.0
        if q["base"] == 0:
            return abs(wi[2]) * INV_PI
        if self.base_smooth:
            return 0.0
        m = _norm(wo + wi)
        m = -m if m[2] < 0.0 else m
        return tr_pdf(wo, m, q["c_alpha"], q["c_alpha"]) / (4.0 * abs(wo @ m))

    @staticmethod
    def usable(s):
        return s is not None and max(s[0]) > 0.0 and s[2] > 0.0 and s[1][2] != 0.0

    def tr(self, dz, w):
        return 1.0 if abs(dz) <= FLT_MIN else math.exp(-abs(dz / w[2]))

    def hg(self, c, g):
        g = min(max(g, -0.99), 0.99)
        d = 1.0 + g * g + 2.0 * g * c
        return 0.25 * INV_PI * (1.0 - g * g) / (d * math.sqrt(max(d, 0.0)))

    def hg_sample(self, wo, g, u):
        g = min(max(g, -0.99), 0.99)
        c = 1.0 - 2.0 * u[0]
        if abs(g) >= 1e-3:
            c = -1.0 / (2.0 * g) * (1.0 + g * g - ((1.0 - g * g) / (1.0 + g - 2.0 * g * u[0])) ** 2)
        s = math.sqrt(max(0.0, 1.0 - c * c))
        phi = 2.0 * math.pi * u[1]
        sign = 1.0 if wo[2] >= 0.0 else -1.0
        a = -1.0 / (sign + wo[2])
        b = wo[0] * wo[1] * a
        t = np.array([1.0 + sign * wo[0] ** 2 * a, sign * b, -sign * wo[0]])
        bt = np.array([b, sign + wo[1] ** 2 * a, -wo[1]])
        return s * math.cos(phi) * t + s * math.sin(phi) * bt + c * wo, self.hg(c, g)

    def entrance_pair(self, wo, wi, r):
        wos = self.top_sample(wo, r(), (r(), r()), True, TRANSMIT)
        if not self.usable(wos):
            return wos, None, False
        wis = self.top_sample(wi, r(), (r(), r()), False, TRANSMIT)
        return wos, wis, self.usable(wis)

    def f(self, wo, wi):
        """LayeredBxDF::f, wo.z > 0 (not times cos)."""
        q = self.p
        wo, wi = np.asarray(wo, np.float64), np.asarray(wi, np.float64)
        if wi[2] <= 0.0:
            return np.zeros(3)
        n = max(q["n_samples"], 1)
        f = n * self.top_f(wo, wi, True)
        r = Rng(walk_key(np.float32(wo), np.float32(wi)))
        th = q["thickness"]
        albedo, g = q["albedo"], q["g"]
        scattering = max(albedo) > 0.0
        exit_z = th
        for _ in range(n):
            wos, wis, ok = self.entrance_pair(wo, wi, r)
            if not ok:
                continue
            beta = wos[0] * abs(wos[1][2]) / wos[2]
            z, w = th, wos[1]
            for depth in range(q["max_depth"]):
                if depth > 3 and max(beta) < 0.25:
                    qq = max(0.0, 1.0 - max(beta))
                    if r() < qq:
                        break
                    beta = beta / (1.0 - qq)
                if not scattering:
                    z = 0.0 if z == th else th
                    beta = beta * self.tr(th, w)
                else:
                    dz = -math.log(1.0 - r()) * abs(w[2])
                    zp = z + dz if w[2] > 0.0 else z - dz
                    if zp == z:
                        continue
                    if 0.0 < zp < th:
                        wt = 1.0 if self.top_smooth else power(wis[2], self.hg(-w @ -wis[1], g))
                        f = f + (beta * albedo * self.hg(-w @ -wis[1], g) * wt * self.tr(zp - exit_z, wis[1])
                                 * wis[0] / wis[2])
                        w_new, ps_pdf = self.hg_sample(-w, g, (r(), r()))
                        if ps_pdf == 0.0 or w_new[2] == 0.0:
                            continue
                        beta = beta * albedo
                        w, z = w_new, zp
                        if ((z < exit_z and w[2] > 0.0) or (z > exit_z and w[2] < 0.0)) and not self.top_smooth:
                            f_exit = self.top_f(-w, wi, True)
                            if max(f_exit) > 0.0:
                                wt = power(ps_pdf, self.top_pdf(-w, wi, TRANSMIT))
                                f = f + beta * self.tr(zp - exit_z, w_new) * f_exit * wt
                        continue
                    z = min(max(zp, 0.0), th)
                if z == exit_z:
                    bs = self.top_sample(-w, r(), (r(), r()), True, REFLECT)
                    if not self.usable(bs):
                        break
                    beta = beta * bs[0] * abs(bs[1][2]) / bs[2]
                    w = bs[1]
                else:
                    if not self.base_smooth:
                        wt = 1.0 if self.top_smooth else power(wis[2], self.base_pdf(-w, -wis[1]))
                        f = f + (beta * self.base_f(-w, -wis[1]) * abs(wis[1][2]) * wt * self.tr(th, wis[1])
                                 * wis[0] / wis[2])
                    bs = self.base_sample(-w, r(), (r(), r()), REFLECT)
                    if not self.usable(bs):
                        break
                    beta = beta * bs[0] * abs(bs[1][2]) / bs[2]
                    w = bs[1]
                    if not self.top_smooth:
                        f_exit = self.top_f(-w, wi, True)
                        if max(f_exit) > 0.0:
                            wt = 1.0 if self.base_smooth else power(bs[2], self.top_pdf(-w, wi, TRANSMIT))
                            f = f + beta * self.tr(th, bs[1]) * f_exit * wt
        return f / n

    def pdf(self, wo, wi):
        """LayeredBxDF::PDF, wo.z > 0."""
        q = self.p
        wo, wi = np.asarray(wo, np.float64), np.asarray(wi, np.float64)
        if wi[2] <= 0.0:
            return 0.0
        n = max(q["n_samples"], 1)
        r = Rng(walk_key(np.float32(wi), np.float32(wo)))
        total = n * self.top_pdf(wo, wi, REFLECT)
        for _ in range(n):
            wos, wis, ok = self.entrance_pair(wo, wi, r)
            if not ok:
                continue
            if self.top_smooth:
                total += self.base_pdf(-wos[1], -wis[1])
                continue
            rs = self.base_sample(-wos[1], r(), (r(), r()), ALL)
            if not self.usable(rs):
                continue
            if self.base_smooth:
                total += self.top_pdf(-rs[1], wi, ALL)
            else:
                r_pdf = self.base_pdf(-wos[1], -wis[1])
                total += power(wis[2], r_pdf) * r_pdf
                t_pdf = self.top_pdf(-rs[1], wi, ALL)
                total += power(rs[2], t_pdf) * t_pdf
        return 0.1 * 0.25 * INV_PI + 0.9 * total / n

"""A ray through a solid SDF glass sphere follows the analytic refracted path.

The ray is carried as the path tracer carries it: intersect -> surface -> smooth-dielectric
scattering (the renderer's microfacet.fresnel_dielectric, refract and reflect, the functions the
BSDF's dielectric lobe is built on, with the lobe chosen by a fixed sample against the Fresnel
reflectance) -> spawn -> intersect from inside -> surface -> scattering again -> spawn -> intersect.
Every quantity is compared with Snell's law and the Fresnel equations evaluated in float64 on the
exact sphere.

Tolerances, from the hit threshold THRESHOLD = 1e-4 (no ray cone, so it is the threshold):
- the marcher stops up to THRESHOLD from the surface, i.e. up to THRESHOLD / cos(incidence)
  before the exact point along the ray (plus a sliver for the sphere's curvature);
- the normal at the stop point differs from the exact one by the angle that offset subtends,
  THRESHOLD tan(incidence) / R, plus the f32 noise of the tetrahedral differences: each of the
  four distances is rounded by ~1e-7 at |p| ~ 1, against differences of 4 h |grad| = 2e-4
  (h = THRESHOLD / 2), so the normal's direction is noisy at ~5e-4 rad, rarely 1e-3;
  NORMAL_NOISE = 2.5e-3 bounds it;
- given the renderer's own normal, Snell's law and the mirror law must hold to f32 accuracy;
- a direction error delta grows into a position error chord * delta at the exit.
Impact parameters stay below 0.9 R (incidence < 64 degrees, cos > 0.43).
"""
import numpy as np
import pytest
import taichi as ti

from renderer.geometry.interface import INF, Ray
from renderer.materials import microfacet as mf
from renderer.scene.description import MaterialSpec
from sdf_helpers import make_geometry, node

vec3 = ti.math.vec3
THRESHOLD = 1e-4
IOR = 1.5
CENTER = np.array([0.2, 0.6, -0.3])
RADIUS = 0.6
GLASS = MaterialSpec("glass", kind="dielectric", base_color=(1.0, 1.0, 1.0), roughness=0.0, ior=IOR)
TRANSMIT = 0.9999  # lobe-choice sample: refract whenever the Fresnel reflectance is below it
REFLECT = 0.0  # reflect whenever the reflectance is above 0
NORMAL_NOISE = 2.5e-3  # f32 noise of the finite-difference normal (module docstring)
F32_DIR = 1e-5  # f32 rounding of a refracted or reflected unit vector

# Rows of the kernel's output (N, 15, 3).
P1, N1, W1, P2, N2, W2, P3, INFO1, INFO2, INFO3, FRESNEL1, FRESNEL2, O2, O3, _ = range(15)


@pytest.fixture(scope="module")
def glass():
    return make_geometry(node("sphere", radius=RADIUS, translate=tuple(CENTER)), materials=(GLASS,),
                         min_threshold=THRESHOLD, over_relaxation=1.6)


@ti.func
def _smooth_dielectric(n, wo, ior, lobe):
    """The smooth glass lobe: n is the outward normal, wo points back along the incoming ray.
    Returns (wi, F, cos_t, entering)."""
    entering = n.dot(wo) >= 0.0
    n_f = n if entering else -n  # the side wo is on
    eta = ior if entering else 1.0 / ior  # n on the far side / n on wo's side
    f, cos_t = mf.fresnel_dielectric(ti.min(1.0, wo.dot(n_f)), eta)
    wi = mf.reflect(wo, n_f)
    if lobe >= f:
        wi = mf.refract(wo, n_f, eta, cos_t)
    return wi, f, cos_t, entering


@ti.kernel
def _through(geo: ti.template(), ior: ti.f32, o: ti.types.ndarray(dtype=vec3, ndim=1),
             d: ti.types.ndarray(dtype=vec3, ndim=1), lobe1: ti.f32, lobe2: ti.f32,
             out: ti.types.ndarray(dtype=vec3, ndim=2)):
    """Entry hit, scattering, spawn, second hit, scattering, spawn, third hit."""
    for i in range(o.shape[0]):
        ray = Ray(o=o[i], d=d[i], cone_width=0.0, cone_spread=0.0)
        for k in ti.static(range(3)):
            hit = geo.intersect(ray, INF)
            out[i, ti.static((INFO1, INFO2, INFO3)[k])] = vec3(hit.hit, hit.t, hit.inside)
            if hit.hit == 1:
                s = geo.surface(ray, hit)
                out[i, ti.static((P1, P2, P3)[k])] = s.p
                if ti.static(k < 2):
                    out[i, ti.static((N1, N2)[k])] = s.n_geo
                    wi, f, cos_t, entering = _smooth_dielectric(s.n_shading, -ray.d, ior, lobe1 if k == 0 else lobe2)
                    out[i, ti.static((W1, W2)[k])] = wi
                    out[i, ti.static((FRESNEL1, FRESNEL2)[k])] = vec3(f, cos_t, 1.0 if entering else 0.0)
                    ray = geo.spawn(s, ti.math.normalize(wi))
                    out[i, ti.static((O2, O3)[k])] = ray.o


def run_through(geo, o, d, lobe1, lobe2):
    o = np.ascontiguousarray(o, np.float32)
    d = np.ascontiguousarray(d, np.float32)
    out = np.zeros((len(o), 15, 3), np.float32)
    _through(geo, IOR, o, d, lobe1, lobe2, out)
    return out.astype(np.float64), o.astype(np.float64), d.astype(np.float64)


# --- float64 references --------------------------------------------------------------------------


def sphere_hits(o, d):
    """Both parameters where the lines o + t d meet the sphere (d unit)."""
    oc = o - CENTER
    b = np.einsum("ij,ij->i", oc, d)
    c = np.einsum("ij,ij->i", oc, oc) - RADIUS ** 2
    root = np.sqrt(b * b - c)
    return -b - root, -b + root


def refract(v, n, eta):
    """Snell's law: v arrives against the unit normal n (v.n < 0); eta = n_far / n_near."""
    cos_i = -np.einsum("ij,ij->i", v, n)
    sin2_t = (1.0 - cos_i ** 2) / eta ** 2
    cos_t = np.sqrt(1.0 - sin2_t)
    return v / eta + (cos_i / eta - cos_t)[:, None] * n


def reflect(v, n):
    return v - 2.0 * np.einsum("ij,ij->i", v, n)[:, None] * n


def fresnel(cos_i, eta):
    """Unpolarised reflectance from the Fresnel equations (s and p averaged); 1 beyond the critical angle."""
    sin2_t = (1.0 - cos_i ** 2) / eta ** 2
    tir = sin2_t >= 1.0
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return np.where(tir, 1.0, 0.5 * (rs ** 2 + rp ** 2))


def _rays_at_impact(rng, n, b_max):
    """Rays from 3 m away towards the sphere, with impact parameters up to b_max * R."""
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    # Two unit vectors across the ray; the impact point sits at radius b in that plane (uniform in area).
    a = np.cross(d, [0.3, 0.5, 0.8])
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    c = np.cross(d, a)
    b = RADIUS * b_max * np.sqrt(rng.uniform(0, 1, n))
    phi = rng.uniform(0, 2 * np.pi, n)
    offset = b[:, None] * (np.cos(phi)[:, None] * a + np.sin(phi)[:, None] * c)
    return CENTER + offset - 3.0 * d, d, b / RADIUS


def normal_tolerance(cos_i):
    """Angle between the normal at the marcher's stop point and the exact one (module docstring)."""
    return THRESHOLD * np.sqrt(1.0 - cos_i ** 2) / cos_i / RADIUS + NORMAL_NOISE


def unit(v):
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _angle(u, v):
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    return np.arccos(np.clip(np.einsum("ij,ij->i", u, v), -1.0, 1.0))


def test_refracted_path_through_a_glass_sphere(glass):
    rng = np.random.default_rng(42)
    o, d, _ = _rays_at_impact(rng, 4000, 0.9)
    out, o, d = run_through(glass, o, d, TRANSMIT, TRANSMIT)

    # Entry: the marcher comes from outside and stops within THRESHOLD before the exact point.
    assert np.all(out[:, INFO1, 0] == 1) and np.all(out[:, INFO1, 2] == 0)
    t1, _ = sphere_hits(o, d)
    p1 = o + t1[:, None] * d
    n1 = (p1 - CENTER) / RADIUS
    cos1 = -np.einsum("ij,ij->i", d, n1)
    assert cos1.min() > 0.43
    f32 = 2e-6  # rounding of positions |p| < 4 along a 3 m ray
    before = t1 - out[:, INFO1, 1]
    assert np.all(before >= -f32)
    assert np.all(before <= 1.01 * THRESHOLD / cos1 + f32)
    assert np.all(np.linalg.norm(out[:, P1] - p1, axis=1) <= 1.01 * THRESHOLD / cos1 + f32)
    normal_tol = normal_tolerance(cos1)
    assert np.all(_angle(out[:, N1], n1) <= normal_tol)
    assert np.median(_angle(out[:, N1], n1)) < 1e-3

    # Inside: refraction by Snell's law, exactly about the normal the surface gave, and within that
    # normal's error of the exact path; the Fresnel split is the one of the Fresnel equations.
    cos1_own = -np.einsum("ij,ij->i", d, unit(out[:, N1]))
    assert np.all(out[:, FRESNEL1, 2] == 1)  # entering
    assert np.allclose(out[:, FRESNEL1, 0], fresnel(cos1_own, IOR), atol=2e-6)
    assert np.all(_angle(out[:, W1], refract(d, unit(out[:, N1]), IOR)) <= F32_DIR)
    w1 = refract(d, n1, IOR)
    dir_tol = normal_tol  # refraction into a denser medium turns a tilted normal's error down
    assert np.all(_angle(out[:, W1], w1) <= dir_tol)
    # The spawned ray starts inside the glass.
    assert np.all(np.linalg.norm(out[:, O2] - CENTER, axis=1) < RADIUS)

    # Exit: the ray marches from inside and meets the back face where the exact chord ends.
    assert np.all(out[:, INFO2, 0] == 1) and np.all(out[:, INFO2, 2] == 1)
    chord = -2.0 * np.einsum("ij,ij->i", w1, p1 - CENTER)
    p2 = p1 + chord[:, None] * w1
    n2 = (p2 - CENTER) / RADIUS
    # The spawned ray starts 2.5 thresholds inside and stops up to one threshold short of the
    # surface: along the exit direction that is at most 3.5 THRESHOLD / cos(exit) = ... / cos1.
    pos_tol = 1.01 * THRESHOLD / cos1 + chord * dir_tol + 3.5 * THRESHOLD / cos1 + f32
    err2 = np.linalg.norm(out[:, P2] - p2, axis=1)
    assert np.all(err2 <= pos_tol), f"exit point off by {err2.max():.2e}"
    # By symmetry the ray leaves at the angle it entered with, and bends back by Snell's law.
    w2 = refract(w1, -n2, 1.0 / IOR)
    assert np.allclose(np.einsum("ij,ij->i", w2, n2), cos1, atol=1e-12)
    assert np.all(out[:, FRESNEL2, 2] == 0)  # leaving
    cos2_own = np.einsum("ij,ij->i", unit(out[:, W1]), unit(out[:, N2]))
    assert np.allclose(out[:, FRESNEL2, 0], fresnel(cos2_own, 1.0 / IOR), atol=2e-6)
    assert np.all(_angle(out[:, W2], refract(unit(out[:, W1]), -unit(out[:, N2]), 1.0 / IOR)) <= F32_DIR)
    # Leaving into the thinner medium magnifies direction errors by up to IOR / cos(exit).
    assert np.all(_angle(out[:, W2], w2) <= IOR / cos1 * (dir_tol + normal_tol))
    # ... and leaves the sphere for good: the third march finds nothing.
    assert np.all(np.linalg.norm(out[:, O3] - CENTER, axis=1) > RADIUS)
    assert np.all(out[:, INFO3, 0] == 0)

    # The tolerances are not loose: the typical errors sit well below them.
    assert np.median(before) < THRESHOLD
    assert np.median(_angle(out[:, W2], w2)) < 2e-3
    assert np.median(err2) < 1e-3


def test_front_reflection_off_a_glass_sphere(glass):
    """Forcing the reflection lobe: the mirror direction about the exact normal, and the reflected
    ray leaves the convex sphere for good."""
    rng = np.random.default_rng(43)
    o, d, _ = _rays_at_impact(rng, 2000, 0.9)
    out, o, d = run_through(glass, o, d, REFLECT, REFLECT)
    t1, _ = sphere_hits(o, d)
    p1 = o + t1[:, None] * d
    n1 = (p1 - CENTER) / RADIUS
    cos1 = -np.einsum("ij,ij->i", d, n1)
    assert np.all(out[:, FRESNEL1, 0] > 0.03)  # so the REFLECT sample picks the mirror lobe
    assert np.all(_angle(out[:, W1], reflect(d, unit(out[:, N1]))) <= F32_DIR)
    assert np.all(_angle(out[:, W1], reflect(d, n1)) <= 2.0 * normal_tolerance(cos1))
    assert np.all(np.linalg.norm(out[:, O2] - CENTER, axis=1) > RADIUS)
    assert np.all(out[:, INFO2, 0] == 0)


def test_total_internal_reflection_inside_a_glass_sphere(glass):
    """From inside, beyond the critical angle asin(1/1.5) = 41.8 degrees, the Fresnel reflectance is 1
    (and cos_t = 0), so the glass reflects whatever the lobe sample; the ray stays in the glass and
    meets the sphere again where the exact reflected chord ends (a whispering-gallery path), where
    the same holds again."""
    critical = np.arcsin(1.0 / IOR)
    rng = np.random.default_rng(44)
    n = 2000
    # Start on a chord at incidence theta > critical: at depth, heading for the point p_hit.
    theta = rng.uniform(critical + 0.02, np.radians(80.0), n)
    normal = rng.normal(size=(n, 3))
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    tangent = np.cross(normal, rng.normal(size=(n, 3)))
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    d = np.cos(theta)[:, None] * normal + np.sin(theta)[:, None] * tangent  # towards the surface
    p_hit = CENTER + RADIUS * normal
    chord = 2.0 * RADIUS * np.cos(theta)
    o = p_hit - (0.5 * chord)[:, None] * d  # the middle of the chord, well inside

    out, o, d = run_through(glass, o, d, TRANSMIT, TRANSMIT)
    # The first hit is from inside (a back face); TRANSMIT would refract if it could.
    assert np.all(out[:, INFO1, 0] == 1) and np.all(out[:, INFO1, 2] == 1)
    _, t_exit = sphere_hits(o, d)
    p1 = o + t_exit[:, None] * d
    n1 = (p1 - CENTER) / RADIUS
    cos1 = np.einsum("ij,ij->i", d, n1)
    assert np.all(np.arccos(cos1) > critical)
    assert np.all(fresnel(cos1, 1.0 / IOR) == 1.0)
    w1 = reflect(d, n1)
    normal_tol = normal_tolerance(cos1)
    for row in (FRESNEL1, FRESNEL2):
        assert np.all(out[:, row, 0] == 1.0) and np.all(out[:, row, 1] == 0.0)  # F = 1, no cos_t
        assert np.all(out[:, row, 2] == 0)  # seen from inside
    assert np.all(np.einsum("ij,ij->i", out[:, W1], n1) < 0.0), "TIR must keep the ray inside"
    assert np.all(_angle(out[:, W1], reflect(d, unit(out[:, N1]))) <= F32_DIR)
    assert np.all(_angle(out[:, W1], w1) <= 2.0 * normal_tol)
    assert np.all(np.linalg.norm(out[:, O2] - CENTER, axis=1) < RADIUS)
    # Second bounce: the same incidence again, so again F = 1 and again a reflection.
    assert np.all(out[:, INFO2, 0] == 1) and np.all(out[:, INFO2, 2] == 1)
    p2 = p1 + (2.0 * RADIUS * cos1)[:, None] * w1
    pos_tol = 1.01 * THRESHOLD / cos1 + 2.0 * RADIUS * cos1 * 2.0 * normal_tol + 3.5 * THRESHOLD / cos1 + 2e-6
    assert np.all(np.linalg.norm(out[:, P2] - p2, axis=1) <= pos_tol)
    assert np.all(np.linalg.norm(out[:, P2] - CENTER, axis=1) > RADIUS - 2 * THRESHOLD)
    assert np.all(np.einsum("ij,ij->i", out[:, W2], (out[:, P2] - CENTER)) < 0.0)


def test_fresnel_matches_the_fresnel_equations():
    """Below the critical angle the renderer's reflectance equals the float64 Fresnel equations; the
    refracted rays above carry exactly this energy split in the path tracer's lobe choice."""
    cos_i = np.linspace(0.01, 1.0, 200)

    @ti.kernel
    def k(c: ti.types.ndarray(dtype=ti.f32, ndim=1), eta: ti.f32, out: ti.types.ndarray(dtype=ti.f32, ndim=2)):
        for i in range(c.shape[0]):
            f, cos_t = mf.fresnel_dielectric(c[i], eta)
            out[i, 0] = f
            out[i, 1] = cos_t

    for eta in (IOR, 1.0 / IOR):
        out = np.zeros((len(cos_i), 2), np.float32)
        k(cos_i.astype(np.float32), eta, out)
        assert np.allclose(out[:, 0], fresnel(cos_i.astype(np.float32).astype(np.float64), eta), atol=2e-6)
        tir = fresnel(cos_i, eta) == 1.0
        assert np.all(out[tir, 1] == 0.0)
        assert tir.any() == (eta < 1.0)

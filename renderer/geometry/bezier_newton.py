"""Ray / Bezier-patch intersection by Newton iteration on (u, phi, t), in the object's frame.

A patch is a u-span of one cubic profile segment times an angular sector of its revolution (see
bezier.py); the BVH over the patches' boxes brings the ray here. Then:

1. the ray is clipped to the patch's object-space box (slab test) -> [t_in, t_out], and re-based at
   t_in, so Newton works with coordinates of the patch's size, not of the camera's distance (f32
   keeps its digits for the surface);
2. Newton solves F(u, phi, s) = S(u, phi) - (base + s d) = 0 with the Jacobian [S_u, S_phi, -d]
   (Cramer's rule). A start is a point of the ray mapped onto the surface: phi is its angle about
   the axis (clamped to the sector), u its foot point on the profile in its meridian plane;
3. a start ends when an iterate leaves the patch's parameters by more than SLACK_U / SLACK_PHI of
   their widths or the ray's box stretch by more than the patch's size (its root, if any, belongs
   to another patch or does not exist), when the Jacobian is singular (the ray is tangent), or
   after MAX_ITERATIONS; it converges when |F| < eps (object units, scaled to the object's size);
4. a converged root counts if it lies inside the patch (up to ACCEPT of the widths, so seams leave
   no cracks) at t in (0, t_max);
5. the first root, not just a root: Newton near tangency can converge to the second root of a
   close pair. The side of the surface a point is on (from its foot point, `meridian`) tells: the ray
   must reach a root from the side it entered the box on. If not, it crossed the surface before,
   and bisection on that side brackets the crossing for a last Newton run (see patch_hit).

A reported hit always satisfies |F| < eps, so it lies on the surface; a ray that does not meet the
patch can only exhaust its attempts, which is a miss.
"""
import taichi as ti

vec3 = ti.math.vec3
vec4 = ti.math.vec4
TWO_PI = 6.283185307179586

MAX_ITERATIONS = 12  # Newton converges quadratically: from a start inside the patch 3 to 5 suffice
# How far (in patch widths) an iterate may wander outside its patch before a start ends. Wider in
# phi: near the axis a ray sweeps through many narrow sectors, and a root found a few sectors away
# still serves the side check (see patch_hit).
SLACK_U = 0.5
SLACK_PHI = 2.0
ACCEPT = 1e-4  # how far (in patch widths) a converged root may lie outside its patch: seam overlap
SAMPLES = 5  # profile samples the foot point search starts from
FOOT_STEPS = 3  # Gauss-Newton steps from the nearest sample to the foot point
SIDE_REACH = 1.0  # how far (in span widths) the foot point may follow the curve beyond its span
BISECTIONS = 12  # halvings of the bracket around a skipped root (to 1/4096 of the stretch)
BEFORE = 1e-3  # the skipped root is sought before (1 - BEFORE) times the found one's distance
# A Jacobian with |det| below this times |S_u| |S_phi| |d| means the ray is tangent to the surface
# to within 1e-6 rad: the step is meaningless (and could overflow), so the start ends.
SINGULAR = 1e-6


@ti.func
def basis(u):
    """Cubic Bernstein basis and its derivative at u."""
    s = 1.0 - u
    b = vec4(s * s * s, 3.0 * s * s * u, 3.0 * s * u * u, u * u * u)
    db = vec4(-3.0 * s * s, 3.0 * s * s - 6.0 * s * u, 6.0 * s * u - 3.0 * u * u, 3.0 * u * u)
    return b, db


@ti.func
def profile(cr, ch, u):
    """(r, h, r', h') of the cubic with radius control values cr and height control values ch."""
    b, db = basis(u)
    return b.dot(cr), b.dot(ch), db.dot(cr), db.dot(ch)


@ti.func
def wrap_angle(phi, rng):
    """phi moved by whole turns to lie nearest the sector rng.zw, then clamped into it."""
    mid = 0.5 * (rng[2] + rng[3])
    delta = phi - mid
    delta -= TWO_PI * ti.floor(delta / TWO_PI + 0.5)
    half = 0.5 * (rng[3] - rng[2])
    return mid + ti.math.clamp(delta, -half, half)


@ti.func
def meridian(cr, ch, q, rng):
    """The foot of q on the span's curve, in q's meridian plane (where the nearest point of a
    surface of revolution lies), and the side of the surface q is on: (u, side), side being
    n . (q - S) with n = (h' cos phi, -r', h' sin phi) (S_u x S_phi over r).

    The foot is the nearest of SAMPLES samples refined by FOOT_STEPS Gauss-Newton steps; near
    grazing the tangent plane Newton starts from must be the one under the ray, or its first step
    jumps to the second root of a close pair. It may follow the curve SIDE_REACH span widths beyond
    the span: there the tangent line at the end would be a poor stand-in for the surface."""
    rho = ti.sqrt(q.x * q.x + q.z * q.z)
    width = rng[1] - rng[0]
    best_u = rng[0]
    best = 3.0e38
    for k in range(SAMPLES):
        u = rng[0] + width * ((k + 0.5) / SAMPLES)
        r, h, dr, dh = profile(cr, ch, u)
        e = (r - rho) * (r - rho) + (h - q.y) * (h - q.y)
        if e < best:
            best = e
            best_u = u
    u = best_u
    for _ in range(FOOT_STEPS):
        r, h, dr, dh = profile(cr, ch, u)
        g = dr * dr + dh * dh
        if g > 0.0:
            u = ti.math.clamp(u - ((r - rho) * dr + (h - q.y) * dh) / g,
                              rng[0] - SIDE_REACH * width, rng[1] + SIDE_REACH * width)
    r, h, dr, dh = profile(cr, ch, u)
    return u, dh * (rho - r) - dr * (q.y - h)


@ti.func
def newton(cr, ch, base, d, u_start, phi_start, s_start, rng, s_lo, s_hi, eps):
    """Newton on S(u, phi) = base + s d. Returns (converged, u, phi, s, iterations)."""
    u = u_start
    phi = phi_start
    s = s_start
    converged = 0
    iterations = 0
    wu = SLACK_U * (rng[1] - rng[0])
    wp = SLACK_PHI * (rng[3] - rng[2])
    for _ in range(MAX_ITERATIONS):
        iterations += 1
        r, h, dr, dh = profile(cr, ch, u)
        c = ti.cos(phi)
        sn = ti.sin(phi)
        f = vec3(r * c, h, r * sn) - (base + s * d)
        if f.dot(f) <= eps * eps:
            converged = 1
            break
        su = vec3(dr * c, dh, dr * sn)
        sp = vec3(-r * sn, 0.0, r * c)
        # Cramer's rule on [su, sp, -d] x = -f, via the cross products of the column pairs.
        bc = d.cross(sp)  # sp x (-d)
        ca = su.cross(d)  # (-d) x su
        ab = su.cross(sp)
        det = su.dot(bc)
        if ti.abs(det) <= SINGULAR * su.norm() * sp.norm() * d.norm():
            break
        inv = 1.0 / det
        u -= f.dot(bc) * inv
        phi -= f.dot(ca) * inv
        s -= f.dot(ab) * inv
        inside = (u >= rng[0] - wu and u <= rng[1] + wu and phi >= rng[2] - wp and phi <= rng[3] + wp
                  and s >= s_lo and s <= s_hi)
        if not inside:
            break
    return converged, u, phi, s, iterations


@ti.func
def accepted(rng, u, phi):
    """Inside the patch, up to ACCEPT of its widths (so that seams leave no cracks)."""
    au = ACCEPT * (rng[1] - rng[0])
    ap = ACCEPT * (rng[3] - rng[2])
    return u >= rng[0] - au and u <= rng[1] + au and phi >= rng[2] - ap and phi <= rng[3] + ap


@ti.func
def patch_hit(cr, ch, rng, lo, hi, o, d, t_max, eps):
    """First hit of the object-space ray o + t d (d need not be unit) on one patch in (0, t_max).
    Returns (hit, t, u, phi, iterations).

    Attempts, in order, until one gives a root in the patch: Newton from the box entry, from the
    exit, from a bracket where the side of the surface (`meridian`) differs between entry and
    exit (bisection first), and from the middle when no attempt converged at all. Then the
    nearest root any attempt converged to (in the patch or just beside it) is checked against
    the side the ray entered on: reaching it from the other side means the ray crossed the
    surface before (a close pair near tangency, where Newton can jump to the second root). Just
    before that root the ray is on the side it crosses from (continuity), so [0, root) brackets
    the earlier crossing, which a last, bounded Newton solves."""
    inv_d = 1.0 / ti.select(ti.abs(d) > 1e-30, d, 1e-30)  # as in the BVH's slab test: no 0 * inf
    t0 = (lo - o) * inv_d
    t1 = (hi - o) * inv_d
    t_in = ti.max(ti.min(t0, t1).max(), 0.0)
    # The box exit is not clipped to t_max: the starts (and so the answer) must not depend on
    # which other patches the traversal happened to test first.
    t_out = ti.max(t0, t1).min()
    hit = 0
    s_best = 0.0
    u_best = 0.0
    phi_best = 0.0
    iterations = 0
    if t_in <= t_out and t_in < t_max:
        base = o + t_in * d
        span = t_out - t_in
        # Newton may wander one patch size (in t) beyond the ray's stretch inside the box.
        reach = (hi - lo).norm() / d.norm()
        s_min = -t_in  # t > 0
        s_max = t_max - t_in
        g_in = 0.0  # side and foot of the box entry (attempt 0 finds them)
        u_in = 0.0
        near = 0  # the nearest converged root, in the patch or not, for the side check
        s_near = 0.0
        crossing = 0.0
        inset = 1e-3 * (rng[1] - rng[0])
        # Every attempt goes through the same call sites of `meridian` and `newton` (Taichi
        # inlines each call site into the traversal).
        for k in range(5):  # 0 entry, 1 exit, 2 bracket entry..exit, 3 middle, 4 before the nearest root
            go = 1
            s0 = 0.0
            s_hi = span + reach
            bracket = 0  # find a change of side in [lo_b, hi_b] first
            probe = 0  # check first that the side at hi_b differs from the entry's
            lo_b = 0.0
            hi_b = 0.0
            if k < 4 and hit == 1:
                go = 0
            elif k == 1:
                s0 = span
            elif k == 2:
                bracket = 1
                probe = 1
                hi_b = span
            elif k == 3:
                # Nothing converged and no change of side: a close pair in the middle is all that
                # is left to look for.
                if near == 1:
                    go = 0
                s0 = 0.5 * span
            elif k == 4:
                # The ray reaches the nearest root from the side it did not enter on: it crossed
                # the surface before. Just before the root it is on the side it crosses from
                # (continuity), so [0, root) brackets that crossing; Newton there stays before it.
                if near == 1 and s_near > 0.0 and crossing * g_in > 0.0:
                    bracket = 1
                    hi_b = s_near * (1.0 - BEFORE)
                    s_hi = hi_b
                else:
                    go = 0
            u_start = 0.0
            g_lo = g_in
            u_lo = u_in
            left = BISECTIONS if bracket == 1 else 0
            if go == 1:
                for _ in range(BISECTIONS + 2):
                    s_eval = s0
                    if probe == 1:
                        s_eval = hi_b
                    elif left > 0:
                        s_eval = 0.5 * (lo_b + hi_b)
                    elif bracket == 1:  # bisection done: start from the bracket's low end
                        s0 = lo_b
                        u_start = u_lo
                        break
                    u_foot, g = meridian(cr, ch, base + s_eval * d, rng)
                    if probe == 1:
                        probe = 0
                        if g * g_in >= 0.0:
                            go = 0
                            break
                    elif left > 0:
                        left -= 1
                        if g * g_lo > 0.0:
                            lo_b = s_eval
                            g_lo = g
                            u_lo = u_foot
                        else:
                            hi_b = s_eval
                    else:
                        u_start = u_foot
                        if k == 0:
                            g_in = g
                            u_in = u_foot
                        break
            if go == 1:
                q = base + s0 * d
                # Starts stay a little inside the span: at an end on the axis (r = 0) S_phi
                # vanishes and the Jacobian is singular.
                u0 = ti.math.clamp(u_start, rng[0] + inset, rng[1] - inset)
                ok, u, phi, s, n = newton(cr, ch, base, d, u0, wrap_angle(ti.atan2(q.z, q.x), rng), s0, rng,
                                          -reach, s_hi, eps)
                iterations += n
                if ok == 1 and s > s_min:
                    # Roots beyond t_max count for the side check too: otherwise the answer would
                    # depend on the order in which the traversal tests patches.
                    if k < 4 and (near == 0 or s < s_near):
                        near = 1
                        s_near = s
                        r, h, dr, dh = profile(cr, ch, u)
                        crossing = dh * (d.x * ti.cos(phi) + d.z * ti.sin(phi)) - dr * d.y
                    if s < s_max and accepted(rng, u, phi) and (hit == 0 or s < s_best):
                        hit = 1
                        s_best = s
                        u_best = u
                        phi_best = phi
    return hit, t_in + s_best, u_best, phi_best, iterations

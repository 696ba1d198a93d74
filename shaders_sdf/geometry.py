"""The SDF side of the geometry interface: sphere tracing with over-relaxation.

Marching (Keinert et al. 2014, 'Enhanced sphere tracing'): each step is omega times the distance
bound. A step is accepted only if the unbounding spheres of its two ends overlap; if they do not,
a surface may lie between, so the marcher goes back to the plain sphere-tracing point and
continues with omega = 1. Hence no accepted step ever crosses a surface, whatever omega is.

The hit threshold grows with the ray cone's width (the pixel footprint), so distant surfaces cost
no more steps than they can show; `min_threshold` floors it where the footprint is tiny.
A ray that starts inside a solid (sdf < 0 at its origin) marches on -sdf, so refracted rays travel
through SDF glass and out again, and a camera inside a solid sees its inner faces.
"""
import numpy as np
import taichi as ti

from renderer.geometry import emitter_shapes
from renderer.geometry.interface import INF, Hit, Ray, Surface, owners_of
from renderer.runtime.upload import upload_fields
from shaders_sdf.scene_sdf import SdfProgram

vec3 = ti.math.vec3

# Spawned rays start this many hit thresholds off the surface: the hit point lies within one
# threshold of it, so 2.5 leaves a margin of 1.5 thresholds before the marcher could stop again.
SPAWN_OFFSET = 2.5
# Adaptive relaxation: weight of the newest slope measurement in the running estimate (Bán and
# Valasek use a similar exponential average; 0.3 follows a change of surface within ~3 steps).
ADAPTIVE_SMOOTHING = 0.3
# The spawned origin must clear every surface by this many thresholds (the march stops below one),
# found in at most this many pushes along the normal (each corrects by the measured shortfall).
SPAWN_CLEARANCE = 1.5
SPAWN_PUSHES = 3
# The least cosine between a hit's normal and the incoming ray, on the side the ray came from.
# Small enough to leave true grazing hits alone, large enough to survive f32 rounding of the dot.
MIN_FACING_COSINE = 1e-3


@ti.data_oriented
class SdfGeometry:
    kind = "sdf"

    def __init__(self, scene, material_index):
        self.program = SdfProgram(scene.sdf_objects, material_index)
        self._node_objects = self.program.node_objects(scene.sdf_objects)
        # march settings are data, so benchmarks sweep them without recompiling
        self.march_f = ti.field(ti.f32, shape=4)  # hit_threshold, min_threshold, max_distance, omega
        self.march_i = ti.field(ti.i32, shape=2)  # max_steps, adaptive (1) or fixed (0) relaxation
        self.set_march(scene.render.march)

    def objects_of(self, prims: np.ndarray) -> np.ndarray:
        """The top-level object (Scene.sdf_objects index) whose tree holds each node; -1 unknown."""
        return owners_of(prims, self._node_objects)

    def set_march(self, march):
        upload_fields([(self.march_f, np.array([march.hit_threshold, march.min_threshold, march.max_distance,
                                                march.over_relaxation], np.float32)),
                       (self.march_i, np.array([march.max_steps, 1 if march.adaptive else 0], np.int32))])

    @ti.func
    def threshold(self, cone_width):
        return ti.max(self.march_f[1], self.march_f[0] * cone_width)

    @ti.func
    def intersect(self, ray, t_max):
        t_limit = ti.min(t_max, self.march_f[2])
        omega_max = self.march_f[3]
        max_steps = self.march_i[0]
        adaptive = self.march_i[1] == 1
        hit = Hit(hit=0, t=t_limit, work=0, tests=0, inside=0, prim=-1, bary=ti.math.vec2(0.0))
        side = 1.0
        t = 0.0
        step = 0.0
        prev_radius = 0.0
        relaxed = False  # the last step was longer than the distance bound: check it
        slope = -1.0  # running estimate of d(distance)/dt along the ray (adaptive mode)
        omega = omega_max
        for i in range(max_steps):
            signed = self.program.distance(ray.o + t * ray.d)
            if i == 0:
                side = 1.0 if signed >= 0.0 else -1.0
                hit.inside = 0 if signed >= 0.0 else 1
            signed *= side
            radius = ti.abs(signed)
            hit.work = i + 1
            if relaxed and (radius + prev_radius < step or signed < 0.0):
                # The unbounding spheres do not overlap, or the step landed on the far side of a
                # surface (head-on at a flat face they only touch and f32 rounding decides): go
                # back to where plain sphere tracing would have stepped, t_prev + prev_radius.
                t += prev_radius - step
                step = prev_radius
                relaxed = False
                slope = -1.0
                if not adaptive:
                    omega = 1.0  # Keinert et al.: no more relaxation on this ray
                continue
            if t > t_limit:
                # Before the hit test: a long step can land past t_max right at a surface (a
                # shadow ray at the emitter it aims for), which is no hit within (0, t_max).
                break
            if radius < self.threshold(ray.cone_width + ray.cone_spread * t):
                hit.hit = 1
                hit.t = t
                break
            factor = omega
            if adaptive:
                if i > 0 and step > 0.0:
                    # Bán and Valasek 2023: fit the distance along the ray as linear with slope m;
                    # the longest step whose end sphere still overlaps is 2 r / (1 - m).
                    measured = ti.math.clamp((radius - prev_radius) / step, -1.0, 1.0)
                    slope += ADAPTIVE_SMOOTHING * (measured - slope)
                factor = ti.min(omega_max, 2.0 / ti.max(1.0 - slope, 1e-3))
            step = signed * factor
            relaxed = factor > 1.0
            prev_radius = radius
            t += step
        return hit

    @ti.func
    def occluded(self, ray, t_max):
        return self.intersect(ray, t_max).hit == 1

    @ti.func
    def trace(self, ray, t_max, any_hit):
        """intersect: sphere tracing finds the first surface along the ray either way."""
        return self.intersect(ray, t_max)

    @ti.func
    def normal_and_material(self, p, h):
        """The normal by tetrahedral central differences (4 evaluations) and (distance, material,
        node) at p (a fifth), all in one loop over one call site of the SDF: each call site
        compiles the whole scene's SDF in again (~0.17 s of kernel load on the showcase)."""
        g = vec3(0.0)
        dmn = vec3(0.0)
        for k in range(5):
            e = vec3(1.0 if (k == 0 or k == 3) else -1.0, 1.0 if k >= 2 else -1.0, 1.0 if (k == 1 or k == 3) else -1.0)
            if k == 4:
                e = vec3(0.0)
            q = self.program.distance_material(p + h * e)
            if k < 4:
                g += e * q.x
            else:
                dmn = q
        length = g.norm()
        n = vec3(0.0, 1.0, 0.0)
        if length > 0.0:
            n = g / length
        return n, dmn

    @ti.func
    def surface(self, ray, hit):
        p = ray.o + hit.t * ray.d
        width = ray.cone_width + ray.cone_spread * hit.t
        eps = self.threshold(width)
        # The normal is the gradient at p itself, by differences at the finest threshold's scale
        # (not the footprint's: the march stops up to a footprint short of the surface, and a
        # footprint-sized step from there reaches past a thin solid or blurs a curved one). For
        # a distance field the gradient at p points at the nearest surface point q and is q's
        # normal, so a ray refracted here and started from q (spawn) sees the surface its
        # direction was refracted at; a blurred normal sent rays into glass beyond the critical
        # angle of the true surface, trapping them by total internal reflection. The step must
        # stay well above f32 resolution at |p| (~6e-8 |p|).
        h = ti.max(0.5 * self.march_f[1], 1e-5 * (1.0 + ti.max(ti.abs(p.x), ti.max(ti.abs(p.y), ti.abs(p.z)))))
        # The side the ray travelled on: the outward normal must face against it from outside
        # and along it from inside.
        along = -ray.d if hit.inside == 0 else ray.d
        n, dmn = self.normal_and_material(p, h)
        if n.dot(n) < 0.5:  # degenerate gradient (never for a proper SDF)
            n = along
        # The march stops within `eps` of a surface, which near a silhouette can be just past the
        # tangent point, where the outward normal already faces away from the ray. Tilt it
        # towards the ray just enough that the ray meets it from the side it travelled on.
        c = n.dot(along)
        if c < MIN_FACING_COSINE:
            n = ti.math.normalize(n + (MIN_FACING_COSINE - c) * along)
        return Surface(p=p, n_geo=n, n_shading=n, uv=ti.math.vec2(0.0), uv1=ti.math.vec2(0.0),
                       tangent=ti.math.vec4(0.0), material=ti.cast(dmn.y, ti.i32), prim=ti.cast(dmn.z, ti.i32),
                       front_face=1 - hit.inside, eps=eps, cone_width=width, cone_spread=ray.cone_spread,
                       color=ti.math.vec4(1.0))

    @ti.func
    def spawn(self, surface, direction):
        outward = direction.dot(surface.n_geo) > 0.0
        side = surface.n_geo if outward else -surface.n_geo
        wanted = 1.0 if outward else -1.0  # the sign of the SDF where the new ray must start
        # Into a solid (refraction, or a reflection inside it) the pixel footprint says how finely
        # the *view* resolves surfaces, not how thick the solid is: a 2 mm glass plate seen with a
        # 5 cm footprint would be jumped over by a footprint-sized offset, and the ray would leave
        # with its entry's 1 / eta^2 but never its exit's. So a ray into a solid first tries to
        # start from the hit point projected onto the surface (the march stopped up to one
        # footprint short of it) and on by a fine clearance, and then marches with the finest
        # threshold (a zero-width cone). Where that projection fails (near a silhouette the
        # tilted normal does not lead to the surface), the footprint-sized offset is used.
        fine = not outward
        coarse_eps = surface.eps
        fine_eps = ti.max(self.march_f[1], 1e-6 * (1.0 + ti.max(ti.abs(surface.p.x),
                                                                ti.max(ti.abs(surface.p.y), ti.abs(surface.p.z)))))
        eps = fine_eps if fine else coarse_eps
        o = surface.p if fine else surface.p + side * (SPAWN_OFFSET * coarse_eps)
        # Near an edge the difference normal blends two faces, and the offset point can land on
        # the wrong side of the other face (a refracted ray starting outside the solid). Push on
        # along the side until the origin clears every surface by the margin the march needs.
        # (Where the ray runs nearly parallel to that other face no push can give it clearance:
        # it then starts within the threshold of that face, which it is about to cross anyway.)
        # One loop holds both attempts: every call site of the SDF compiles it in again.
        pushes = 0
        for _ in range(2 * SPAWN_PUSHES + 1):
            clearance = wanted * self.program.distance(o)
            if clearance >= SPAWN_CLEARANCE * eps:
                break
            if fine and pushes == SPAWN_PUSHES:
                fine = False
                eps = coarse_eps
                o = surface.p + side * (SPAWN_OFFSET * coarse_eps)
                pushes = 0
                continue
            if not fine and pushes == SPAWN_PUSHES:
                break
            # Aim past the required clearance, at the spawn offset: aiming at exactly the
            # clearance leaves the next check to f32 rounding, and a sub-ulp shortfall can never
            # be pushed away.
            o += side * (SPAWN_OFFSET * eps - clearance)
            pushes += 1
        width = 0.0 if fine else surface.cone_width
        # The spawned ray keeps the footprint it arrived with but does not grow it further: a
        # threshold that grew along a grazing ray faster than the ray leaves a convex surface
        # would let the ray find its own surface again.
        return Ray(o=o, d=direction, cone_width=width, cone_spread=0.0)

    # --- direct lighting ---------------------------------------------------------------------------
    def primitive_count(self) -> int:
        return self.program.node_count

    def emitter_info(self) -> dict:
        """The nodes `sample_emitter` can sample: top-level spheres (a sphere's solid angle can be
        sampled exactly; other emissive SDF shapes are found by BSDF sampling alone)."""
        materials = self.program.material_ids  # >= 0 only on top-level objects
        ids = [i for i, node in enumerate(self.program.order) if node.kind == "sphere" and materials[i] >= 0]
        nodes = [self.program.order[i] for i in ids]
        centre = np.array([n.transform.translate for n in nodes], np.float64).reshape(-1, 3)
        radius = np.array([n.param("radius") * n.transform.scale for n in nodes], np.float64)
        count = len(ids)
        return {"prim": np.array(ids, np.int32), "material": materials[ids] if count else np.zeros(0, np.int32),
                "area": 4 * np.pi * radius ** 2, "lo": centre - radius[:, None], "hi": centre + radius[:, None],
                "axis": np.tile([0.0, 1.0, 0.0], (count, 1)), "theta_o": np.full(count, np.pi),
                "theta_e": np.full(count, np.pi / 2)}

    @ti.func
    def material_of(self, node):
        return self.program.material[node]

    @ti.func
    def _sphere(self, node):
        return self.program.translation[node], self.program.params[node].x * self.program.scale[node]

    @ti.func
    def sample_emitter(self, node, ref, u):
        centre, radius = self._sphere(node)
        return emitter_shapes.sphere_sample(centre, radius, ref, u)

    @ti.func
    def emitter_pdf(self, node, ref, p, n):
        centre, radius = self._sphere(node)
        return emitter_shapes.sphere_pdf(centre, radius, ref, p, n)

    @ti.func
    def next_segment(self, surface, direction, target, target_n, to_target):
        """The next ray leaving `surface` and how far to trace it: along `direction` without a
        limit, or (to_target) towards `target`, stopping short of the target's own surface by the
        offset a spawned ray keeps from it. One spawn call site serves continuation and shadow
        rays alike: every call site of the SDF compiles it in again."""
        d = direction
        if to_target:
            d = ti.math.normalize(target - surface.p)
        ray = Ray(o=surface.p, d=d, cone_width=surface.cone_width, cone_spread=surface.cone_spread)
        margin = 0.0
        if surface.eps >= 0.0:
            ray = self.spawn(surface, d)
            margin = SPAWN_OFFSET * surface.eps
        else:  # a point in a medium: no surface to leave; the target's offset at its range
            margin = SPAWN_OFFSET * self.threshold(surface.cone_width + surface.cone_spread * (target - surface.p).norm())
        t_max = INF
        if to_target:
            # The march finds a surface once its distance falls below the threshold; near the
            # target that distance is the remaining length times the cosine at the target, so a
            # ray meeting the target obliquely must stop further short (cosine floored at 0.05:
            # at most 20 margins, rather than an unbounded gap at the silhouette).
            cos_target = ti.max(ti.abs(d.dot(target_n)), 0.05)
            t_max = (target - ray.o).dot(d) - margin / cos_target
        return ray, t_max

    @ti.func
    def visible(self, surface, target, target_n):
        """No surface between `surface` and `target` (nothing to march when the target lies within
        the spawn offset)."""
        ray, t_max = self.next_segment(surface, target - surface.p, target, target_n, True)
        blocked = False
        if t_max > 0.0:
            blocked = self.intersect(ray, t_max).hit == 1
        return not blocked

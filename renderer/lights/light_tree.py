"""A light BVH for choosing one of many emitters in proportion to its estimated contribution.

After Conty Estevez and Kulla 2018, "Importance sampling of many lights with adaptive tree
splitting" (the stochastic single-path traversal, without the adaptive splitting): every node
bounds its emitters by a box, their total power and an orientation cone; a shading point walks
from the root to one emitter, choosing at each interior node between the two children in
proportion to an importance that estimates how much each child's emitters can light the point.

The tree itself (emitter bounds, split rule, node layout) is built on the host by
``renderer.lights.light_tree_build``; this module uploads it and walks it.

Device side
-----------
``LightTree.select(p, n, u) -> (emitter, pmf)`` and ``LightTree.pmf(p, n, emitter) -> pmf``.
The importance of a node for a point p with normal n (``node_importance``) is the paper's::

    power * cos(theta') * |cos(theta_i')| / max(d^2, D2_CLAMP * (diagonal / 2)^2)

with d the distance from p to the box centre, theta_b the half angle of the box's bounding sphere
seen from p (pi when p is inside it), theta_w the angle between the cone axis and the direction
from the centre to p, theta' = max(0, theta_w - theta_o - theta_b) (no emitter of the node faces
p more directly) and theta_i' = max(0, theta_i - theta_b), theta_i the angle between n and the
direction to the centre (the factor is 1 when n is zero, e.g. in a medium). The importance is 0
when theta' >= theta_e: no emitter of the node can light p.

The clamp on d^2 (which keeps a node whose centre is near p from taking all the probability)
is an eighth of the squared bounding radius, ``D2_CLAMP`` = 1/8, rather than the whole: measured
by the exact variance of the one-sample estimate sum_e f_e / pmf_e (f_e: a triangle's point-light
contribution), a clamp at the bounding radius gave 3.8x (a 20 m ceiling of 10,000 panel
triangles, 12 points under it) and 4x (3,000 random triangles, 12 points among them) the relative
variance of the 1/8 clamp; 1/4 was in between, and clamps below 1/8 gained nothing more.

Conservative: a node that holds an emitter able to light p must never get importance 0 (its
emitters would get pmf 0, and the estimate would lose their light). theta' is a lower bound on
every emitter's angle, but f32 rounding of acos near 0 and pi is up to about 5e-4 rad, so the
cut-off is at ``theta_e + ANGLE_SLACK`` (2e-3 rad), and both cosines are clamped from below by
``COS_FLOOR`` so that a node just inside the cut-off keeps a small positive weight. When both
children have importance 0 (no emitter below can light p) the choice falls back to power so
that the pmf over all emitters still sums to 1.

The random number is rescaled at every level, so deep trees use up its 24 bits: selection
probabilities below about 2^-24 relative to a sibling are not resolved (as in every f32
implementation of this method). ``pmf`` is computed from the same importances, so it never
disagrees with what ``select`` returns.
"""
import math

import numpy as np
import taichi as ti

from renderer.lights.light_tree_build import SMALL_NODE, EmitterBounds, build_light_tree
from renderer.runtime.upload import upload_fields

__all__ = ["LightTree", "node_importance"]

PI = math.pi

# Importance guards (see the module docstring). Angles in radians.
ANGLE_SLACK = 2e-3  # > 4x the worst f32 acos error near 0 or pi (sqrt(2 * 2^-23) ~ 5e-4)
COS_FLOOR = 1e-4  # the smallest weight a node within the cut-off keeps, relative to facing it
INSIDE_SLACK = 1e-5  # p counts as inside the bounding sphere up to this relative margin (f32)
D2_CLAMP = 0.125  # d^2 >= D2_CLAMP * (diagonal / 2)^2 (see the module docstring)
D2_FLOOR = 1e-12  # m^2: the clamp for a point-sized node; power / D2_FLOOR stays finite in f32
U_MAX = 1.0 - 2.0 ** -24  # the largest f32 below 1


@ti.func
def node_importance(p, n, lo, hi, axis, power, theta_o, theta_e):
    """The paper's importance of a node (box lo/hi, cone axis/theta_o/theta_e, power) for the
    point p with normal n (zero: no receiver cosine). Never 0 for a node that holds an emitter
    able to light p (see the module docstring)."""
    result = 0.0
    if power > 0.0:
        centre = 0.5 * (lo + hi)
        half_diag2 = 0.25 * (hi - lo).norm_sqr()
        v = p - centre
        d2 = v.norm_sqr()
        theta_b = PI
        to_p = ti.math.vec3(0.0, 0.0, 1.0)  # only used when p is outside the bounding sphere
        if d2 > half_diag2 * (1.0 + INSIDE_SLACK) and d2 > 0.0:
            to_p = v / ti.sqrt(d2)
            theta_b = ti.asin(ti.min(ti.sqrt(half_diag2 / d2), 1.0))
        # Angles from atan2(|cross|, dot), not acos(dot): acos amplifies a 1-ulp change of a
        # cosine near 1 into ~3e-4 rad, so the same importance computed at two call sites
        # (select and pmf) could disagree by 1e-4 relative.
        theta_w = ti.atan2(axis.cross(to_p).norm(), axis.dot(to_p))
        theta_p = ti.max(theta_w - theta_o - theta_b, 0.0)
        if theta_p < theta_e + ANGLE_SLACK:
            cos_p = ti.max(ti.cos(theta_p), COS_FLOOR)
            cos_i = 1.0
            n2 = n.norm_sqr()
            if n2 > 0.0:
                theta_i = ti.atan2(n.cross(to_p).norm(), ti.abs(n.dot(to_p)))
                cos_i = ti.max(ti.cos(ti.max(theta_i - theta_b, 0.0)), COS_FLOOR)
            result = power * cos_p * cos_i / ti.max(d2, D2_CLAMP * half_diag2, D2_FLOOR)
    return result


@ti.data_oriented
class LightTree:
    """The light tree on the device; ``select`` / ``pmf`` as every light selector has them."""

    kind = "tree"

    def __init__(self, emitters: EmitterBounds, *, max_leaf_size: int = 1, bins: int = 12,
                 small_node: int = SMALL_NODE):
        self.options = dict(max_leaf_size=max_leaf_size, bins=bins, small_node=small_node)
        self.data = build_light_tree(emitters, **self.options)
        d = self.data
        m, n = d.num_nodes, d.num_emitters
        self.num_emitters = n
        self.node_lo = ti.Vector.field(3, ti.f32, shape=m)
        self.node_hi = ti.Vector.field(3, ti.f32, shape=m)
        self.node_axis = ti.Vector.field(3, ti.f32, shape=m)
        # (power, theta_o, theta_e) and (right child or -1, first, count)
        self.node_scalars = ti.Vector.field(3, ti.f32, shape=m)
        self.node_links = ti.Vector.field(3, ti.i32, shape=m)
        self.order = ti.field(ti.i32, shape=n)
        self.rank = ti.field(ti.i32, shape=n)
        self.leaf_power = ti.field(ti.f32, shape=n)  # power in leaf order
        self._upload()

    def _upload(self) -> None:
        d = self.data
        upload_fields([(self.node_lo, d.node_lo), (self.node_hi, d.node_hi), (self.node_axis, d.node_axis),
                       (self.node_scalars, np.stack([d.node_power, d.node_theta_o, d.node_theta_e], 1)),
                       (self.node_links, np.stack([d.node_right, d.node_first, d.node_count], 1)),
                       (self.order, d.order), (self.rank, d.rank), (self.leaf_power, d.emitter_power[d.order])])

    def refit(self, emitters: EmitterBounds) -> bool:
        """The tree built again for the emitters' new powers, into the same fields where it has as
        many nodes (else False, nothing changed)."""
        data = build_light_tree(emitters, **self.options)
        if (data.num_nodes, data.num_emitters) != (self.data.num_nodes, self.data.num_emitters):
            return False
        self.data = data
        self._upload()
        return True

    @ti.func
    def importance(self, p, n, node):
        s = self.node_scalars[node]
        return node_importance(p, n, self.node_lo[node], self.node_hi[node], self.node_axis[node],
                               s[0], s[1], s[2])

    @ti.func
    def _left_probability(self, p, n, node, right):
        """(probability of the left child, of the right child) at an interior node."""
        il = self.importance(p, n, node + 1)
        ir = self.importance(p, n, right)
        if il + ir <= 0.0:
            # no emitter below can light p: by power, so that the pmf still sums to 1
            il = self.node_scalars[node + 1][0]
            ir = self.node_scalars[right][0]
        pl = 0.5
        pr = 0.5
        total = il + ir
        if total > 0.0:  # 0 only below a node of power 0, which select never enters
            pl = il / total
            pr = ir / total
        return pl, pr

    @ti.func
    def select(self, p, n, u):
        """(emitter i32, pmf f32) for the point p with normal n and a uniform u in [0, 1)."""
        node = 0
        pmf = 1.0
        v = ti.math.clamp(u, 0.0, U_MAX)  # a copy: the caller's u stays as it was
        while self.node_links[node][0] >= 0:
            right = self.node_links[node][0]
            pl, pr = self._left_probability(p, n, node, right)
            if v < pl:
                v = v / pl
                pmf *= pl
                node = node + 1
            else:
                v = (v - pl) / pr
                pmf *= pr
                node = right
            v = ti.math.clamp(v, 0.0, U_MAX)
        first = self.node_links[node][1]
        count = self.node_links[node][2]
        chosen = first
        if count > 1:
            total = 0.0
            for k in range(count):
                total += self.leaf_power[first + k]
            if total > 0.0:
                target = v * total
                acc = 0.0
                found = False
                for k in range(count):
                    w = self.leaf_power[first + k]
                    if not found and w > 0.0:
                        chosen = first + k  # the last positive one if rounding runs past the end
                        acc += w
                        if target < acc:
                            found = True
                pmf *= self.leaf_power[chosen] / total
            else:
                chosen = first + ti.min(ti.cast(v * count, ti.i32), count - 1)
                pmf /= ti.cast(count, ti.f32)
        return self.order[chosen], pmf

    @ti.func
    def pmf(self, p, n, emitter):
        """The probability that ``select(p, n, .)`` returns ``emitter``."""
        r = self.rank[emitter]
        node = 0
        pmf = 1.0
        while self.node_links[node][0] >= 0:
            right = self.node_links[node][0]
            pl, pr = self._left_probability(p, n, node, right)
            if r < self.node_links[right][1]:
                pmf *= pl
                node = node + 1
            else:
                pmf *= pr
                node = right
        first = self.node_links[node][1]
        count = self.node_links[node][2]
        if count > 1:
            total = 0.0
            for k in range(count):
                total += self.leaf_power[first + k]
            if total > 0.0:
                pmf *= self.leaf_power[r] / total
            else:
                pmf /= ti.cast(count, ti.f32)
        return pmf

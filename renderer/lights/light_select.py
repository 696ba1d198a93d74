"""Choosing one emitter among many for next-event estimation.

Every selector is a ``@ti.data_oriented`` object with the same two Taichi funcs, so an integrator
can take any of them:

``select(p, n, u) -> (emitter i32, pmf f32)``
    one emitter for the shading point p with normal n (zero in a medium: no cosine) from a
    uniform u in [0, 1), and the probability of having chosen it;
``pmf(p, n, emitter) -> f32``
    that probability for a given emitter (for MIS, when a BSDF sample hits an emitter).

and, on the host, ``refit(emitters) -> bool``: the same emitters with other powers (an emission
edit) taken in place, into the same fields, so the kernels that hold the selector need no compile;
False where the selector's sizes would change (a light tree of another shape): build it anew then.

Kinds
-----
``"uniform"`` (``UniformSelector``)
    every emitter with probability 1 / N; ignores p and n.
``"power"`` (``PowerSelector``)
    in proportion to power, through an alias table (Walker 1977, built with Vose's method):
    O(1) per sample; ignores p and n.
``"tree"`` (``renderer.lights.light_tree.LightTree``)
    the light BVH of Conty Estevez and Kulla 2018: in proportion to an estimate of the emitter's
    contribution at p (distance, orientation, power); O(depth) per sample.
``"auto"``
    ``"tree"`` when there are more than ``AUTO_TREE_MIN`` (64) emitters, else ``"power"``: with
    few emitters the tree's per-sample cost (two importance evaluations per level) buys little,
    with many the 1/d^2 falloff makes power alone a poor guide.
``"single"`` (``SingleEmitterSelector``)
    what every kind means for a scene with one emitter: that one, with probability 1, without
    reading u. The kernels then never draw the selection's random number (LLVM drops the unused
    draw), which on the Cornell box with the sobol sampler is ~4.6% of a sample's time.

All selectors take the emitters as a ``renderer.lights.light_tree_build.EmitterBounds``.
"""
from __future__ import annotations

import numpy as np
import taichi as ti

from renderer.lights.light_tree import LightTree
from renderer.lights.light_tree_build import EmitterBounds, triangle_emitters
from renderer.runtime.upload import upload_fields

__all__ = ["SELECTOR_KINDS", "AUTO_TREE_MIN", "SingleEmitterSelector", "UniformSelector", "PowerSelector", "LightTree",
           "EmitterBounds", "triangle_emitters", "alias_table", "resolve_kind",
           "make_light_selector"]

SELECTOR_KINDS = ("auto", "uniform", "power", "tree")
AUTO_TREE_MIN = 64  # "auto" builds a tree for more emitters than this


@ti.data_oriented
class SingleEmitterSelector:
    """The one emitter of a scene that has one: chosen with probability 1, u unread."""

    kind = "single"

    def __init__(self, emitters: EmitterBounds | int):
        n = emitters if isinstance(emitters, int) else len(emitters)
        if n != 1:
            raise ValueError(f"a single-emitter selector needs exactly one emitter, not {n}")
        self.num_emitters = 1

    def refit(self, emitters: EmitterBounds) -> bool:
        return len(emitters) == 1

    @ti.func
    def select(self, p, n, u):
        return 0, 1.0

    @ti.func
    def pmf(self, p, n, emitter):
        return 1.0


@ti.data_oriented
class UniformSelector:
    """Every emitter with probability 1 / N."""

    kind = "uniform"

    def __init__(self, emitters: EmitterBounds | int):
        n = emitters if isinstance(emitters, int) else len(emitters)
        if n < 1:
            raise ValueError("a light selector needs at least one emitter")
        self.num_emitters = n
        self.count = ti.field(ti.i32, shape=())
        self.count[None] = n

    def refit(self, emitters: EmitterBounds) -> bool:
        return len(emitters) == self.num_emitters

    @ti.func
    def select(self, p, n, u):
        count = self.count[None]
        e = ti.min(ti.cast(u * count, ti.i32), count - 1)
        return ti.max(e, 0), 1.0 / ti.cast(count, ti.f32)

    @ti.func
    def pmf(self, p, n, emitter):
        return 1.0 / ti.cast(self.count[None], ti.f32)


def alias_table(weights) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vose's alias method: (q (N,) f32, alias (N,) i32, pmf (N,) f32) for weights >= 0 with a
    positive sum. Column j (chosen with probability 1 / N) gives j when a second uniform number
    is below q[j], else alias[j]; pmf is weights / sum.

    The pairing is sequential (a Python loop over the columns: about 50 ms per 100k weights);
    the selectors only need it once per scene.
    """
    w = np.asarray(weights, np.float64)
    if w.ndim != 1 or w.shape[0] == 0:
        raise ValueError("weights must be a non-empty 1-d array")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError("weights must be finite and >= 0")
    total = w.sum()
    if not total > 0:
        raise ValueError("the weights sum to 0")
    n = w.shape[0]
    scaled = w * (n / total)
    q = np.ones(n)
    alias = np.arange(n)
    small = [int(i) for i in np.flatnonzero(scaled < 1.0)]
    large = [int(i) for i in np.flatnonzero(scaled >= 1.0)]
    s = scaled.tolist()
    while small and large:
        i = small.pop()
        j = large[-1]
        q[i] = s[i]
        alias[i] = j
        s[j] = (s[j] + s[i]) - 1.0
        if s[j] < 1.0:
            large.pop()
            small.append(j)
    # what remains is 1 up to rounding
    return q.astype(np.float32), alias.astype(np.int32), (w / total).astype(np.float32)


@ti.data_oriented
class PowerSelector:
    """Emitters in proportion to their power, O(1) per sample through an alias table."""

    kind = "power"

    def __init__(self, emitters: EmitterBounds):
        q, alias, pmf = alias_table(np.asarray(emitters.power, np.float64))
        n = q.shape[0]
        self.num_emitters = n
        self.q = ti.field(ti.f32, shape=n)
        self.alias = ti.field(ti.i32, shape=n)
        self.table_pmf = ti.field(ti.f32, shape=n)
        upload_fields([(self.q, q), (self.alias, alias), (self.table_pmf, pmf)])

    def refit(self, emitters: EmitterBounds) -> bool:
        if len(emitters) != self.num_emitters:
            return False
        q, alias, pmf = alias_table(np.asarray(emitters.power, np.float64))
        upload_fields([(self.q, q), (self.alias, alias), (self.table_pmf, pmf)])
        return True

    @ti.func
    def select(self, p, n, u):
        count = self.q.shape[0]
        x = ti.math.clamp(u, 0.0, 1.0) * count
        j = ti.min(ti.cast(x, ti.i32), count - 1)
        e = j
        if x - ti.cast(j, ti.f32) >= self.q[j]:
            e = self.alias[j]
        return e, self.table_pmf[e]

    @ti.func
    def pmf(self, p, n, emitter):
        return self.table_pmf[emitter]


def resolve_kind(kind: str, num_emitters: int) -> str:
    """The concrete kind ("single", "uniform", "power" or "tree") that ``kind`` means for that
    many emitters (every kind is "single" for one)."""
    if kind not in SELECTOR_KINDS:
        raise ValueError(f"unknown light selector '{kind}' (known: {', '.join(SELECTOR_KINDS)})")
    if num_emitters == 1:
        return "single"
    if kind == "auto":
        return "tree" if num_emitters > AUTO_TREE_MIN else "power"
    return kind


def make_light_selector(kind: str, emitters: EmitterBounds, **tree_options):
    """A selector of the given kind ("auto", "uniform", "power" or "tree") over the emitters.
    ``tree_options`` (max_leaf_size, bins, small_node) go to ``LightTree``."""
    concrete = resolve_kind(kind, len(emitters))
    if concrete == "single":
        return SingleEmitterSelector(emitters)
    if concrete == "uniform":
        return UniformSelector(emitters)
    if concrete == "power":
        return PowerSelector(emitters)
    return LightTree(emitters, **tree_options)

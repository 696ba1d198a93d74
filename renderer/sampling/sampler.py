"""Samplers: where an integrator's random numbers come from.

Every sampler is a pure function of (pixel, sample index, dimension, seed): no state lives on the
device, images are reproducible and independent of thread scheduling, and any sample can be
recomputed alone. An integrator asks for numbers by *dimension id*: each decision of a path uses
its own id (see `renderer.sampling.dims`), so no two decisions correlate.

  state = sampler.start(pixel, index, seed)      once per camera sample
  sampler.get1d(state, dim) -> f32 in [0, 1)
  sampler.get2d(state, dim) -> vec2 in [0, 1)^2  (a well-stratified pair where the sampler has one)

Which sampler is compiled in is a per-program choice (`SAMPLERS`).
"""
import taichi as ti

from renderer.sampling.names import SAMPLERS
from renderer.sampling.rng import SampleState, pcg_hash, sample_key, uniform
from renderer.sampling.sobol import SobolSampler


@ti.data_oriented
class IndependentSampler:
    """Independent uniform numbers: a hash of (pixel, index, seed) then of the dimension."""

    name = "independent"

    @ti.func
    def start(self, pixel, index, seed):
        return SampleState(pixel=ti.cast(pixel, ti.u32), index=ti.cast(index, ti.u32), seed=ti.cast(seed, ti.u32),
                           key=sample_key(pixel, index, seed))

    @ti.func
    def get1d(self, state, dim):
        return uniform(state.key, dim)

    @ti.func
    def get2d(self, state, dim):
        # Two hashes of distinct dimension ids; the second id is far from any id in use.
        return ti.math.vec2(uniform(state.key, dim), uniform(state.key, dim + 0x4000))


def make_sampler(name: str):
    if name == "independent":
        return IndependentSampler()
    if name == "sobol":
        return SobolSampler()
    raise ValueError(f"unknown sampler '{name}' (choose from {', '.join(SAMPLERS)})")


__all__ = ["SampleState", "IndependentSampler", "make_sampler", "SAMPLERS", "pcg_hash"]

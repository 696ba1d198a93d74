"""Sampling: where random numbers come from, and what turns them into directions and choices.

rng.py                counter-based hashes (a pure function of pixel, sample, dimension, seed)
sampler.py            the samplers an integrator draws from (independent, sobol.py's Owen-scrambled
                      Sobol points); names.py lists them for scene files
dims.py               the dimension id of every decision a path makes
warps.py              unit square -> disc, hemisphere, frames
cdf.py                inverting a tabulated CDF (binary search)
"""

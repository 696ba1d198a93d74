"""Integrators: each computes the radiance (or a debug quantity) carried by one camera ray.

An integrator is a data-oriented class with
  name, description                 for the command line, HUD and help
  hotkey                            the viewer's letter for it (Taichi's window reports letters only)
  display_tonemapper                None (the user's choice) or a tone mapper name its output wants
  li(ctx, ray, state, max_depth)    a Taichi func returning (value, stats, albedo, normal), all vec3:
                                    stats = (geometry work, primitive tests, rays traced) for this
                                    sample; albedo and normal are the denoising AOVs (renderer/film/aovs.py)
  writes_aovs                       whether li's albedo and normal mean anything (else zeros)
  denoisable                        whether its image is light a denoiser may clean (not debug views)
`ctx` is the RenderProgram: ctx.geometry, ctx.bsdf, ctx.environment, ctx.sampler, ctx.features;
`state` is the camera sample's sampler state (renderer.sampling.sampler).

A multi-pass integrator (sppm) has no `li`; it provides make_program(renderer, features, sampler,
lights) returning a RenderProgram subclass with `sliced = False` whose advance(width, height,
steps, first_step, seed, max_depth, *camera) runs steps of its own whole-image iterations
(ROUND_SLICES steps an iteration) and returns how many it ran, and
`noise_estimate = False` when its film holds an estimate rather than a mean of samples.
"""
from renderer.integrators.debug import VIEWS
from renderer.integrators.nee_mis import MultipleImportanceSampling, NextEventEstimation
from renderer.integrators.path import PathTracer
from renderer.integrators.sppm import StochasticProgressivePhotonMapping

# Name -> the integrator's class, or a debug view's row (renderer/integrators/debug.py): either has
# the attributes above, and calling it makes the integrator.
_ALL = (MultipleImportanceSampling, NextEventEstimation, PathTracer, *VIEWS, StochasticProgressivePhotonMapping)
INTEGRATORS = {entry.name: entry for entry in _ALL}


def integrator_names() -> list[str]:
    return list(INTEGRATORS)


def make_integrator(name: str):
    try:
        return INTEGRATORS[name]()
    except KeyError:
        raise ValueError(f"unknown integrator '{name}' (known: {', '.join(INTEGRATORS)})") from None

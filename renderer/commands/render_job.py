"""The command line's render job: what `render` and its animations take from the options (and from a
checkpoint being resumed), with the checks that refuse a job in one line before Taichi starts."""
from __future__ import annotations

from dataclasses import replace

from renderer.commands.headless import RenderJob
from renderer.film.adaptive import DEFAULT_MIN_SPP
from renderer.output.checkpoint import CheckpointHeader
from renderer.output.render_outputs import denoise_refusal


def job_from_arguments(args, scene, previous: CheckpointHeader | None) -> RenderJob:
    """The command line's job; on --resume, the checkpoint's settings where the line names none."""
    spp, seconds = args.spp, args.seconds
    if previous is not None and spp is None and seconds is None:
        spp, seconds = previous.spp_target, previous.seconds_budget
    exposure = args.exposure if args.exposure is not None else (
        previous.exposure if previous else scene.render.exposure)
    job = RenderJob(spp=spp, seconds=seconds, size=args.size, integrator=args.integrator, max_depth=args.max_depth,
                    seed=args.seed, exposure=exposure, tonemapper=args.tonemapper, denoise=bool(args.denoise),
                    aovs=args.aovs, noise_threshold=args.noise_threshold,
                    min_spp=args.min_spp if args.min_spp is not None else DEFAULT_MIN_SPP,
                    packets=getattr(args, "packets", None) or 0)
    if previous is not None:
        job = replace(job, size=job.size or (previous.width, previous.height),
                      integrator=job.integrator or previous.integrator,
                      max_depth=previous.max_depth if job.max_depth is None else job.max_depth,
                      seed=previous.seed if job.seed is None else job.seed,
                      tonemapper=job.tonemapper or previous.tonemapper,
                      denoise=previous.denoise if args.denoise is None else args.denoise,
                      aovs=job.aovs or previous.aovs,
                      noise_threshold=(previous.noise_threshold if job.noise_threshold is None
                                       else job.noise_threshold),
                      min_spp=previous.min_spp if args.min_spp is None else job.min_spp,
                      packets=previous.packets if getattr(args, "packets", None) is None else job.packets)
    return job.resolved(scene)


def check_denoising(job: RenderJob) -> None:
    """--denoise and --noise-threshold refused in one line before Taichi starts where they cannot work."""
    from renderer.output.denoise import unavailable_reason
    from renderer.integrators import make_integrator

    if job.denoise:
        reason = unavailable_reason()
        if reason:
            raise ValueError(f"--denoise: {reason}")
        refusal = denoise_refusal(job.integrator)
        if refusal:
            raise ValueError(f"--denoise: {refusal}")
    if job.noise_threshold is not None and hasattr(make_integrator(job.integrator), "make_program"):
        raise ValueError(f"--noise-threshold: {job.integrator} renders whole-image iterations; adaptive sampling "
                         "works with path, nee, mis and the debug views")

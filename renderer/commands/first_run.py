"""`python app.py` without a display: the default scene rendered headless, a new user's first image.

That image should be the best its time buys: denoised by Intel Open Image Denoise where pyoidn is
installed (`render --denoise`: the raw render is kept beside it as OUT.raw.png), the raw render
with a one-line note where it is not. `python app.py --no-denoise` keeps it raw. The `render`
command itself stays raw unless asked (--denoise): its images are estimates that tests, references
and benchmarks compare, and that a denoiser would change.
"""
from __future__ import annotations

FIRST_RUN_SPP = 32


def first_run_arguments(denoise: bool = True) -> tuple[list[str], str]:
    """The `render` command line of the first run, and the line that announces it."""
    from renderer.output.denoise import unavailable_reason
    from renderer.scene.catalog import DEFAULT_SCENE

    argv = ["render", DEFAULT_SCENE, "--spp", str(FIRST_RUN_SPP)]
    said = "no display: rendering the default scene headless instead of opening the viewer"
    if not denoise:
        return [*argv, "--no-denoise"], f"{said}; not denoised (--no-denoise)"
    reason = unavailable_reason()
    if reason:
        return [*argv, "--no-denoise"], f"{said}; not denoised: {reason}"
    return [*argv, "--denoise"], (f"{said}; the image will be denoised, the raw render kept beside it "
                                  "(python app.py --no-denoise: the raw render only)")

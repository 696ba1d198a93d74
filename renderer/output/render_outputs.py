"""What `render --denoise` and `--aovs` add to a render's files.

--denoise: the image written to --out is Open Image Denoise's output (renderer/output/denoise.py), fed the
render's colour and, where the integrator writes them, its albedo and normal AOVs. The raw render
is kept beside it, in the same format: OUT.raw.png (tone-mapped as OUT) or OUT.raw.exr (linear),
so the estimate itself is never lost to a denoised image.
--aovs: the layers beside the colour: `albedo`, `normal` (the denoising AOVs), `variance` (of each
pixel's mean), `raw` (the colour before denoising, with --denoise), `spp` (samples each pixel took)
and `stopped` (1 where adaptive sampling stopped the pixel). In an .exr --out they are layers of
the same file (albedo.R, albedo.G ...); beside a .png they go to one EXR named OUT.aovs.exr.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from renderer.film.adaptive import STOPPED
from renderer.output.denoise import DenoiseInput, Denoiser
from renderer.integrators import make_integrator

AOVS_SUFFIX = ".aovs.exr"
RAW_SUFFIX = ".raw"  # before the extension: OUT.raw.png beside a denoised OUT.png


def denoise_input(result) -> DenoiseInput:
    """The render's colour and, when its integrator wrote them, its AOVs."""
    state = result.state
    if make_integrator(result.integrator).writes_aovs and state is not None and state.albedo is not None:
        return DenoiseInput(result.image, state.albedo, state.normal)
    return DenoiseInput(result.image)


def denoise_refusal(integrator: str) -> str | None:
    """Why --denoise cannot apply to `integrator`'s images (one line), or None."""
    if not make_integrator(integrator).denoisable:
        return f"the {integrator} view is not an image of light; denoise path, nee, mis or sppm renders"
    return None


def denoised(result, denoiser: Denoiser | None = None) -> np.ndarray:
    """The render's image denoised (render_command has refused integrators it does not apply to)."""
    return (denoiser or Denoiser()).denoise(denoise_input(result))


def aov_layers(result, raw: np.ndarray | None) -> dict[str, np.ndarray]:
    """The --aovs layers of a finished render (`raw`: the colour before denoising, if it was)."""
    state = result.state
    layers = {}
    if state.albedo is not None and make_integrator(result.integrator).writes_aovs:
        layers["albedo"] = state.albedo
        layers["normal"] = state.normal
    if result.variance is not None:
        layers["variance"] = result.variance
    if raw is not None:
        layers["raw"] = raw
    layers["spp"] = (state.count + state.rejected).astype(np.float32)
    if state.adaptive is not None:
        layers["stopped"] = (state.adaptive == STOPPED).astype(np.float32)
    return layers


def aovs_path(out: Path) -> Path:
    """Where the AOVs of a render to `out` go: `out` itself for an EXR, else OUT.aovs.exr."""
    return out if out.suffix.lower() == ".exr" else out.with_name(out.stem + AOVS_SUFFIX)


def raw_path(out: Path) -> Path:
    """Where a denoised render to `out` keeps its raw image: OUT.raw.png beside OUT.png."""
    return out.with_name(out.stem + RAW_SUFFIX + out.suffix)

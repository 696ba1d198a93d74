"""Test helper: a Mitsuba 3 XML file rendered by Lantern and by Mitsuba 3, each as (mean, variance of
the mean) per pixel and channel, for tests.stats.image_tests.assert_agree. Mitsuba's variance comes
from the spread of independent passes (variance of the pass images / passes). Tests using it are
skipped where Mitsuba 3 (the project's optional `reference` extra) is not installed."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from renderer.camera import CameraFrame
from renderer.renderer import Renderer
from renderer.scene.mitsuba import load_mitsuba_scene


def mitsuba_or_skip():
    """The mitsuba module with its variant set, or the test skipped."""
    pytest.importorskip("mitsuba", reason="Mitsuba is the project's optional `reference` extra")
    from renderer.bench.mitsuba_side import MitsubaUnavailable, _import_mitsuba

    try:
        return _import_mitsuba()[0]
    except MitsubaUnavailable as error:
        pytest.skip(str(error))


def lantern_image(path: Path, spp: int, seed: int = 7) -> tuple[np.ndarray, np.ndarray]:
    scene = load_mitsuba_scene(path)
    renderer = Renderer(scene)
    renderer.render(CameraFrame.from_spec(scene.camera), spp, seed=seed)
    return (renderer.film.mean_image().astype(np.float64),
            renderer.film.variance_of_mean_image().astype(np.float64))


def mitsuba_image(path: Path, spp: int, passes: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    from renderer.bench.mitsuba_side import render_scene

    mi = mitsuba_or_skip()
    scene = mi.load_file(str(path))
    images = np.stack([render_scene(scene, spp, seed=seed + k).astype(np.float64) for k in range(passes)])
    return images.mean(axis=0), images.var(axis=0, ddof=1) / passes

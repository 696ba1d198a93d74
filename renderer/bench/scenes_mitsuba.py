"""`bench scenes --mitsuba`: each research scene as Lantern reads it, converted to Mitsuba 3's
scene dictionary (renderer/bench/mitsuba_scene_dict.py, as `compare` does) and rendered by Mitsuba
at the bench's size and path length for the same seconds, its mean beside Tungsten's reference
over the same pixels. Where Lantern and Tungsten disagree, this says whether the difference is in
the file as read (Mitsuba agrees with Lantern) or in Lantern (Mitsuba agrees with Tungsten). A
scene that does not convert (a kind Mitsuba lacks, such as pbrt's coated materials) gives the
reason instead."""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from renderer.bench.common import describe_error


def mitsuba_side(scene, size: tuple[int, int], max_depth: int, seconds: float) -> dict:
    """Mitsuba's figures for one loaded scene: load and first-render seconds, samples per second,
    its image (under "_image"), or "mitsuba_note" saying why there is none."""
    from renderer.bench.mitsuba_scene_dict import scene_dict
    from renderer.bench.mitsuba_side import MitsubaUnavailable, _import_mitsuba

    try:
        mi, variant, _ = _import_mitsuba()
    except MitsubaUnavailable as error:
        return {"mitsuba_note": f"Mitsuba 3 is not installed ({error})"}
    with tempfile.TemporaryDirectory(prefix="lantern-scenes-") as mesh_dir:
        try:
            t0 = time.perf_counter()
            description, notes = scene_dict(scene, Path(mesh_dir), size, max_depth=max_depth)
            loaded = mi.load_dict(description)
            load_s = time.perf_counter() - t0
        except Exception as error:  # noqa: BLE001 - a scene that does not convert is a note, not a crash
            return {"mitsuba_note": f"does not convert: {describe_error(error)}"}
        t0 = time.perf_counter()
        mi.render(loaded, spp=1, seed=0)  # JIT-compiles
        start_s = time.perf_counter() - t0
        # As its users run it: one render call for the whole budget, sized by a short warm call
        # (a series of small calls runs slower per sample).
        t0 = time.perf_counter()
        mi.render(loaded, spp=4, seed=1)
        rate = 4 / max(time.perf_counter() - t0, 1e-6)
        spp = max(1, round(rate * seconds))
        t0 = time.perf_counter()
        image = np.array(mi.render(loaded, spp=spp, seed=2), dtype=np.float64)[..., :3]
        render_s = time.perf_counter() - t0
    return {"mitsuba_variant": variant, "mitsuba_load_s": load_s, "mitsuba_start_s": start_s, "mitsuba_spp": spp,
            "mitsuba_render_s": render_s, "mitsuba_samples_per_s": spp * size[0] * size[1] / render_s,
            "mitsuba_notes": notes, "_image": image}

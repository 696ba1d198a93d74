"""A scene file's grid medium (`[media.NAME] type = "grid"`) made into its density and albedo grids.

The density comes from a Mitsuba .vol file (vol_files.py) and fills the box `box_min`..`box_max`,
or the file's own bounding box where the scene gives none; the albedo is a constant or a second
.vol file over the same box. Bad values are one line naming the field (GridFieldError, which the
loader reports with the scene file) or the .vol file (SceneError).
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from renderer.scene.description import VolumeGridSpec
from renderer.scene.limits import MemoryLedger
from renderer.scene.vol_files import read_vol

VOL_EXTENSIONS = (".vol",)
GRID_FILTERS = ("trilinear", "nearest")


class GridFieldError(ValueError):
    """A problem with one field of a grid medium: (field, message)."""

    def __init__(self, field: str, message: str):
        super().__init__(field, message)
        self.field, self.message = field, message


def grid_volumes(values: dict, resolve: Callable[[str], Path], ledger: MemoryLedger | None) -> dict:
    """{"density", "albedo"}: VolumeGridSpecs of a grid medium's fields (the schema's MEDIUM),
    `resolve(field)` the file a field names."""
    density_file = resolve("file")
    density = read_vol(density_file, ledger)
    if np.min(density.values) < 0.0:
        raise GridFieldError("file", f"{density_file.name} holds negative densities")
    to_world = box_to_world(values["box_min"], values["box_max"], density.bounds)
    nearest = values["filter"] == "nearest"
    if values["albedo_file"] is None:
        colour = tuple(float(c) for c in values["albedo"])
        albedo = VolumeGridSpec(np.array(colour, np.float32).reshape(1, 1, 1, 3), constant=colour)
    else:
        albedo_file = resolve("albedo_file")
        albedo = VolumeGridSpec(read_vol(albedo_file, ledger).values, to_world=to_world, nearest=nearest,
                                file=albedo_file)
    return {"density": VolumeGridSpec(density.values, to_world=to_world, nearest=nearest, file=density_file),
            "albedo": albedo}


def box_to_world(box_min, box_max, file_bounds) -> tuple[tuple[float, ...], ...]:
    """The map of the unit cube onto the box (the file's bounds where the scene gives none)."""
    given = box_min is not None or box_max is not None
    if given and (box_min is None or box_max is None):
        raise GridFieldError("box_min" if box_min is None else "box_max", "box_min and box_max come together")
    lo, hi = (np.array(c, np.float64) for c in ((box_min, box_max) if given else file_bounds))
    if np.any(hi <= lo):
        where = "box_max" if given else "file"
        raise GridFieldError(where, f"the box {tuple(lo)}..{tuple(hi)} has no inside (each max above its min)")
    matrix = np.diag([*(hi - lo), 1.0])
    matrix[:3, 3] = lo
    return tuple(tuple(float(x) for x in row) for row in matrix)

"""A scene's grid media on the device: one GridMediumRecord per medium (NO_GRID for the others),
their density and albedo grids as GridVolume rows, and every grid's voxels in one float field.

Data, like the homogeneous table: a scene may hold any number of grid media without compiling
anything new; only whether it has one is compile-time (Features.has_grid_media). The fields are
allocated for every scene (one row and one voxel where it has none), so the cost benchmark can
compile the tracking code into any scene; they are uploaded only where the scene has a grid
medium (so a scene without one launches no upload of its own). Left zero, every medium reads as
a grid of majorant 0: no collisions, transmittance 1.
"""
import numpy as np
import taichi as ti

from renderer.media import grid
from renderer.media.grid import NO_GRID, GridMediumRecord, GridVolume
from renderer.runtime.upload import upload_fields

MAJORANT_MARGIN = 1.0 + 2.0 ** -20


def pack_grids(media) -> tuple[dict, dict, np.ndarray]:
    """(medium columns, volume columns, voxels) of a scene's media (MediumSpec, kind "grid" or not)."""
    columns = {"density": [], "albedo": [], "scale": [], "majorant": []}
    volumes = {"row0": [], "row1": [], "row2": [], "res": [], "offset": [], "channels": [], "nearest": []}
    chunks, offset = [], 0

    def add_volume(spec) -> int:
        nonlocal offset
        values = np.asarray(spec.values, np.float32)
        to_local = np.linalg.inv(np.asarray(spec.to_world, np.float64))
        for r in range(3):
            volumes[f"row{r}"].append(to_local[r])
        volumes["res"].append(values.shape[2::-1])
        volumes["offset"].append(offset)
        volumes["channels"].append(values.shape[3])
        volumes["nearest"].append(int(spec.nearest))
        chunks.append(values.ravel())
        offset += values.size
        return len(volumes["offset"]) - 1

    for medium in media:
        row = {"density": NO_GRID, "albedo": NO_GRID, "scale": 0.0, "majorant": 0.0}
        if medium.kind == "grid":
            # The largest density bounds both lookups; raised by a few f32 ulps so that the device's
            # rounded scale * density never exceeds it (any bound keeps the tracking exact).
            majorant = medium.scale * float(np.max(medium.density.values)) * MAJORANT_MARGIN
            row = {"density": add_volume(medium.density), "albedo": add_volume(medium.albedo),
                   "scale": medium.scale, "majorant": majorant}
        for name, value in row.items():
            columns[name].append(value)
    voxels = np.concatenate(chunks) if chunks else np.zeros(1, np.float32)
    return columns, volumes, voxels


@ti.data_oriented
class GridMedia:
    def __init__(self, media):
        columns, volumes, voxels = pack_grids(media)
        self.records = GridMediumRecord.field(shape=max(1, len(columns["density"])))
        self.volumes = GridVolume.field(shape=max(1, len(volumes["offset"])))
        self.voxels = ti.field(ti.f32, shape=max(1, len(voxels)))
        if not volumes["offset"]:
            return
        upload_fields([(self.voxels, np.asarray(voxels, np.float32)),
                       (self.records, {"density": np.array(columns["density"], np.int32),
                                       "albedo": np.array(columns["albedo"], np.int32),
                                       "scale": np.array(columns["scale"], np.float32),
                                       "majorant": np.array(columns["majorant"], np.float32)}),
                       (self.volumes, {
                           **{f"row{r}": np.array(volumes[f"row{r}"], np.float32) for r in range(3)},
                           "res": np.array(volumes["res"], np.int32),
                           "offset": np.array(volumes["offset"], np.int32),
                           "channels": np.array(volumes["channels"], np.int32),
                           "nearest": np.array(volumes["nearest"], np.int32)})])

    @ti.func
    def holds(self, medium):
        """Whether medium `medium` (an index of the media table) is a grid."""
        return self.records[medium].density != NO_GRID

    @ti.func
    def free_flight(self, medium, ray, t_max, throughput, key):
        return grid.delta_tracking(self.records, self.volumes, self.voxels, medium, ray.o, ray.d, t_max,
                                   throughput, key)

    @ti.func
    def transmittance(self, medium, ray, t_end, key):
        return grid.ratio_tracking(self.records, self.volumes, self.voxels, medium, ray.o, ray.d, t_end, key)

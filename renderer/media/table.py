"""A scene's participating media on the device, and what fills the space between objects.

Media are data (a struct row each), so a scene may hold any number without compiling anything
new; only whether media occur at all is compile-time (Features.has_media). Grid media keep their
grids in `grids` (grid_table.py); their rows here hold only the phase function's g.
"""
import numpy as np
import taichi as ti

from renderer.materials.table import NO_MEDIUM
from renderer.media.grid_table import GridMedia
from renderer.runtime.upload import upload_fields

vec3 = ti.math.vec3
MediumRecord = ti.types.struct(sigma_a=vec3, sigma_s=vec3, g=ti.f32)


@ti.data_oriented
class MediaTable:
    def __init__(self, scene, volume_media: tuple = ()):
        """volume_media: media of model files' materials (glTF volumes), numbered after the scene's."""
        media = tuple(scene.media) + tuple(volume_media)
        self.table = MediumRecord.field(shape=max(1, len(media)))
        if media:
            upload_fields([(self.table, {"sigma_a": np.array([m.sigma_a for m in media], np.float32),
                                         "sigma_s": np.array([m.sigma_s for m in media], np.float32),
                                         "g": np.array([m.g for m in media], np.float32)})])
        self.grids = GridMedia(media)
        fog = scene.fog
        # Data, not constants: editing a medium or the fog recompiles nothing.
        self.scene_medium = ti.field(ti.i32, shape=())
        self.scene_medium[None] = scene.medium_names().index(fog.medium) if fog.model == "medium" else NO_MEDIUM
        self.fog = ti.Vector.field(4, ti.f32, shape=())  # analytic fog: colour rgb, density
        # Density 0 unless the scene asks for analytic fog: a kernel compiled with it (the cost
        # benchmark forces every effect on) then leaves the image as it is.
        self.fog[None] = (*fog.color, fog.density if fog.model == "analytic" else 0.0)

    @ti.func
    def outside(self):
        """The medium around every object (where the camera is), or NO_MEDIUM."""
        return self.scene_medium[None]

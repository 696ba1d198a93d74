"""The environment seen by rays that leave the scene: an equirectangular HDR map, a sky gradient or
a constant colour. Which of the three is compiled in is a `Features` decision; intensity and rotation
are data (a small field), so the viewer's sliders never recompile a kernel.

Map convention, Mitsuba 3's `envmap` (src/emitters/envmap.cpp) texel for texel: u = atan2(d.x,
-d.z) / 2pi (u = 0 looks along -z, u = 1/4 along +x), v = acos(d.y) / pi. Column j's centre is at
u = (j + 1/2) / W, and u wraps. Row i's centre is at v = i / (H - 1): row 0 is the zenith itself and
the last row the nadir ("align corners" in v; v clamps). `rotation` turns the map about +y by the
right-hand rule (counter-clockwise seen from above), as Mitsuba's `to_world` rotate([0, 1, 0],
rotation): the texel at map azimuth phi is seen at phi - rotation.

Any other orientation (EnvironmentSpec.needs_matrix: a tilted axis, a Mitsuba `to_world` that
moves the poles) is a 3x3 orthogonal matrix R from the map's frame to the world's, compiled in only
for such scenes (Features.environment_rotated): a direction d is looked up at R^T d, as Mitsuba's
`envmap` looks it up at to_world^-1 d, and samples drawn in the map's frame leave as R d. R has a
unit Jacobian, so the sampler's solid-angle pdf is unchanged. Scenes without it compile exactly the
azimuth offset above.
"""
import math

import numpy as np
import taichi as ti

from renderer.sampling.warps import PI
from renderer.runtime.upload import upload_fields


def row_edges(height: int) -> np.ndarray:
    """Polar angles (height + 1,) bounding each map row's share of the sphere: halfway between row
    centres (pi i / (height - 1)), and 0 and pi at the ends, so the first and last rows own half a
    row each around the poles. The environment sampler's cells; float64."""
    inner = math.pi * (np.arange(1, height) - 0.5) / max(height - 1, 1)
    return np.concatenate([[0.0], inner, [math.pi]])


@ti.data_oriented
class Environment:
    def __init__(self, spec, image: np.ndarray | None):
        """spec: EnvironmentSpec; image: (H, W, 3) float32 for kind 'map', else None."""
        self.kind = spec.kind
        if self.kind == "map":
            if image is None:
                raise ValueError("an environment map needs its image")
            self.height, self.width = image.shape[:2]
            self.texels = ti.Vector.field(3, ti.f32, shape=(self.height, self.width))
            upload_fields([(self.texels, image)])
        # intensity, rotation (radians), and the three sky / constant colours
        self.scalars = ti.field(ti.f32, shape=2)
        self.colors = ti.Vector.field(3, ti.f32, shape=3)
        # Static: the full rotation is compiled in only where the scene's orientation needs it.
        self.rotated = spec.needs_matrix
        if self.rotated:
            self.frame = ti.Matrix.field(3, 3, ti.f32, shape=())  # map frame -> world
        self.set_spec(spec)

    def set_spec(self, spec):
        """Intensity, orientation and colours (data: no recompile). A spec that needs the full
        rotation needs an environment built with one."""
        if spec.needs_matrix and not self.rotated:
            raise ValueError("this environment was compiled for turns about +y only; its orientation "
                             "needs a new Environment")
        colours = [spec.color, spec.zenith, spec.horizon] if spec.kind == "constant" else [spec.zenith, spec.horizon, spec.ground]
        # with the matrix compiled in, the matrix carries all of the orientation (azimuth offset 0)
        angle = 0.0 if self.rotated else math.radians(spec.y_rotation() or 0.0)
        uploads = [(self.scalars, np.array([spec.intensity, angle], np.float32)),
                   (self.colors, np.array(colours, np.float32))]
        if self.rotated:
            uploads.append((self.frame, spec.rotation_matrix().astype(np.float32)))
        upload_fields(uploads)

    @ti.func
    def to_map(self, d):
        """A world direction in the environment's own frame (where the map convention holds)."""
        local = d
        if ti.static(self.rotated):
            local = self.frame[None].transpose() @ d  # orthogonal: the transpose is the inverse
        return local

    @ti.func
    def from_map(self, local):
        """A direction of the environment's own frame in the world."""
        d = local
        if ti.static(self.rotated):
            d = self.frame[None] @ local
        return d

    @ti.func
    def radiance(self, d):
        value = ti.math.vec3(0.0)
        if ti.static(self.kind == "map"):
            value = self._lookup(self.to_map(d))
        elif ti.static(self.kind == "sky"):
            value = self._sky(self.to_map(d))
        else:
            value = self.colors[0]
        return value * self.scalars[0]

    @ti.func
    def _sky(self, d):
        zenith, horizon, ground = self.colors[0], self.colors[1], self.colors[2]
        y = ti.math.clamp(d.y, -1.0, 1.0)
        result = ti.math.mix(horizon, ground, ti.min(1.0, -y * 8.0))  # a short fade below the horizon
        if y >= 0.0:
            result = ti.math.mix(horizon, zenith, ti.sqrt(y))
        return result

    @ti.func
    def _lookup(self, d):
        """Bilinear lookup of a direction in the map's frame; wraps in u, clamps in v (texel centres
        as in the module doc)."""
        phi = ti.atan2(d.x, -d.z) + self.scalars[1]
        u = phi / (2.0 * PI)
        u -= ti.floor(u)
        v = ti.acos(ti.math.clamp(d.y, -1.0, 1.0)) / PI
        x = u * self.width - 0.5
        y = ti.math.clamp(v * (self.height - 1), 0.0, self.height - 1.0)
        x0f = ti.floor(x)
        y0f = ti.floor(y)
        fx = x - x0f
        fy = y - y0f
        x0 = ti.cast(x0f, ti.i32) % self.width
        x0 = x0 + self.width if x0 < 0 else x0
        x1 = (x0 + 1) % self.width
        y0 = ti.cast(y0f, ti.i32)
        y1 = ti.min(y0 + 1, self.height - 1)
        top = ti.math.mix(self.texels[y0, x0], self.texels[y0, x1], fx)
        bottom = ti.math.mix(self.texels[y1, x0], self.texels[y1, x1], fx)
        return ti.math.mix(top, bottom, fy)

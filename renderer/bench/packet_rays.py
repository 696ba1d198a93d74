"""Packets of rays from numpy arrays through renderer/packets/traversal.py: what the tests hold to
the scalar traversal and scripts/packet_speed.py times."""
import numpy as np
import taichi as ti

from renderer.geometry.interface import INF
from renderer.packets import traversal


@ti.data_oriented
class PacketShooter:
    """Closest hits and blockers of many rays, `width` rays a packet in the order given (the last
    packet padded with rays that are not rays: t_max -1)."""

    def __init__(self, geometry, width=8, one_at_a_time=False):
        """one_at_a_time: each packet's rays through traversal.trace_lanes (the scalar walk lane by
        lane, as the packet path traces a large world's bounce and shadow rays)."""
        self.geometry = geometry
        self.width = width
        self.one_at_a_time = one_at_a_time

    @ti.kernel
    def _shoot(self, o: ti.types.ndarray(dtype=ti.math.vec3), d: ti.types.ndarray(dtype=ti.math.vec3),
               t_max: ti.types.ndarray(), any_hit: ti.template(), prim: ti.types.ndarray(), t: ti.types.ndarray()):
        lanes = ti.static(self.width)
        for p in range(o.shape[0] // lanes):
            ox, oy, oz = ti.Vector([0.0] * lanes), ti.Vector([0.0] * lanes), ti.Vector([0.0] * lanes)
            dx, dy, dz = ti.Vector([0.0] * lanes), ti.Vector([0.0] * lanes), ti.Vector([0.0] * lanes)
            tm = ti.Vector([0.0] * lanes)
            for k in ti.static(range(lanes)):
                i = p * lanes + k
                ox[k], oy[k], oz[k] = o[i].x, o[i].y, o[i].z
                dx[k], dy[k], dz[k] = d[i].x, d[i].y, d[i].z
                tm[k] = t_max[i]
            g, tt = ti.cast(tm * 0.0, ti.i32), tm
            if ti.static(self.one_at_a_time):
                g, tt, b1, b2, lane_visits, lane_tests = traversal.trace_lanes(self.geometry, ox, oy, oz, dx, dy, dz,
                                                                               tm, any_hit)
            else:
                g, tt, b1, b2, visits, tests = traversal.trace(self.geometry, ox, oy, oz, dx, dy, dz, tm, any_hit)
            for k in ti.static(range(lanes)):
                prim[p * lanes + k] = g[k]
                t[p * lanes + k] = tt[k]

    def _run(self, origins, directions, t_max, any_hit):
        n = len(origins)
        padded = -(-n // self.width) * self.width
        o = np.zeros((padded, 3), np.float32)
        d = np.zeros((padded, 3), np.float32)
        d[:, 2] = 1.0
        tm = np.full(padded, -1.0, np.float32)
        o[:n], d[:n] = origins, directions
        tm[:n] = t_max
        prim = np.zeros(padded, np.int32)
        t = np.zeros(padded, np.float32)
        self._shoot(o, d, tm, any_hit, prim, t)
        return t[:n], prim[:n]

    def closest(self, origins, directions, t_max=INF):
        """(t, prim) of each ray's closest hit in (0, t_max); a miss has t = INF and prim -1."""
        t, prim = self._run(origins, directions, t_max, False)
        t[prim < 0] = INF
        return t, prim

    def occluded(self, origins, directions, t_max=INF):
        """1 where something lies along the ray within (0, t_max)."""
        _, prim = self._run(origins, directions, t_max, True)
        return (prim >= 0).astype(np.int32)

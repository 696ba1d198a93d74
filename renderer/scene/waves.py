"""Water surfaces as a sum of directional (Gerstner) waves: the wave set, its surface and normals,
and the checks that keep the surface a valid, single-sheeted mesh. Numpy only, float64.

A wave i has a direction of travel d_i = (cos a_i, sin a_i) in the (x, z) plane (a_i in degrees,
from +x towards +z), a wavelength L_i (wavenumber k_i = 2 pi / L_i), an amplitude A_i, a phase
phi_i (degrees) and a Gerstner steepness Q_i in [0, 1]. A point p0 = (x0, z0) of the flat grid
moves to

    theta_i = k_i (d_i . p0) + phi_i
    y       = sum_i A_i cos(theta_i)
    (x, z)  = p0 - sum_i Q_i A_i d_i sin(theta_i)

(GPU Gems 1, chapter 1, with the horizontal term signed so that crests sharpen: points near a
crest, theta = 0, move toward it). Q = 0 gives plain sine waves (a height field); Q = 1 with one
wave gives the trochoid of a deep-water wave with circular orbits.

Normals are analytic: the cross product of the surface's partial derivatives,
    dP/dx0 = (1 - sum Q A k dx^2 cos, -sum A k dx sin, -sum Q A k dx dz cos)
    dP/dz0 = (-sum Q A k dx dz cos, -sum A k dz sin, 1 - sum Q A k dz^2 cos)
    n = dP/dz0 x dP/dx0    (= (-dh/dx, 1, -dh/dz) when every Q is 0)

Self-intersection. The horizontal map p0 -> p0 - f(p0) has Jacobian I - sum_i c_i cos(theta_i)
d_i d_i^T with c_i = Q_i k_i A_i; the norm of the sum is at most C = sum_i c_i. If C < 1 the map is
injective (p0 - f(p0) is f's Lipschitz bound C away from a contraction) and its Jacobian positive
definite: no loops, no folded or degenerate triangle, and n.y > 0 everywhere. At C = 1 crests can
become cusps with no normal; above, crests loop through themselves. `problems` refuses C >= 1.

Sampling. A wave shorter than two grid cells cannot be represented by the grid (it aliases into
a longer, wrong wave); `problems` refuses it too.

Random sets: `random_waves(count, wavelength, amplitude, direction, spread, steepness, seed)` draws
`count` waves from numpy's default_rng(seed): wavelengths log-uniform in [wavelength / 4,
wavelength], amplitudes amplitude * L_i / wavelength (every wave equally steep, as in a wind sea's
spectrum), directions uniform in direction +- spread degrees, phases uniform in [0, 360), the given
steepness for all. C is then count * steepness * 2 pi amplitude / wavelength for any seed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable, Optional, Sequence

import numpy as np

SHORTEST_FRACTION = 0.25  # a random set's shortest wavelength, as a fraction of its longest


@dataclass(frozen=True)
class Wave:
    wavelength: float  # metres, > 0
    amplitude: float  # metres, >= 0
    direction: float = 0.0  # degrees, direction of travel, from +x towards +z
    phase: float = 0.0  # degrees
    steepness: float = 0.0  # Gerstner Q in [0, 1]; 0 is a sine wave

    @property
    def wavenumber(self) -> float:
        return 2.0 * math.pi / self.wavelength

    @property
    def loop_factor(self) -> float:
        """Q k A: this wave's share of the no-self-intersection budget (the sum must stay < 1)."""
        return self.steepness * self.wavenumber * self.amplitude


def random_waves(count: int, wavelength: float, amplitude: float, direction: float, spread: float,
                 steepness: float, seed: int) -> tuple[Wave, ...]:
    rng = np.random.default_rng(seed)
    draws = rng.random((count, 3))
    waves = []
    for a, b, c in draws:
        length = wavelength * SHORTEST_FRACTION ** a  # log-uniform in [wavelength / 4, wavelength]
        waves.append(Wave(direction=float(direction + spread * (2.0 * b - 1.0)), wavelength=float(length),
                          amplitude=float(amplitude * length / wavelength), phase=float(360.0 * c),
                          steepness=float(steepness)))
    return tuple(waves)


def loop_sum(waves: Iterable[Wave]) -> float:
    return float(sum(w.loop_factor for w in waves))


def problems(waves: Sequence[Wave], cell: float, names: Optional[Sequence[str]] = None) -> Optional[str]:
    """A one-line description of what makes these waves unusable on a grid of `cell` metres, or
    None. `names[i]` is how a message refers to wave i (e.g. "waves[2]")."""
    names = names or [f"wave {i}" for i in range(len(waves))]
    for name, w in zip(names, waves):
        if not w.wavelength > 0.0:
            return f"{name}: wavelength must be positive, got {w.wavelength:g}"
        if w.wavelength < 2.0 * cell:
            return (f"{name}: wavelength {w.wavelength:g} m is shorter than two grid cells "
                    f"({2.0 * cell:g} m = 2 * size / resolution): the grid cannot represent it; "
                    f"raise resolution or lengthen the wave")
    total = loop_sum(waves)
    if total >= 1.0:
        return (f"steepness too high: the sum over the waves of steepness * 2 pi * amplitude / wavelength "
                f"is {total:.3g}, it must stay below 1 or the Gerstner crests loop and the surface "
                f"intersects itself; lower steepness or amplitude")
    return None


def surface(waves: Sequence[Wave], x0: np.ndarray, z0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(positions (..., 3), unit normals (..., 3)) of the displaced points of the grid (x0, z0)."""
    x0 = np.asarray(x0, np.float64)
    z0 = np.asarray(z0, np.float64)
    shape = np.broadcast(x0, z0).shape
    x, y, z = np.array(np.broadcast_to(x0, shape)), np.zeros(shape), np.array(np.broadcast_to(z0, shape))
    # Partial derivatives dP/dx0 = (xx, xy, xz) and dP/dz0 = (zx, zy, zz).
    xx, xy, xz = np.ones(shape), np.zeros(shape), np.zeros(shape)
    zx, zy, zz = np.zeros(shape), np.zeros(shape), np.ones(shape)
    for w in waves:  # one wave at a time: memory stays O(vertices) for any wave count
        a = math.radians(w.direction)
        dx, dz, k = math.cos(a), math.sin(a), w.wavenumber
        theta = k * (dx * x0 + dz * z0) + math.radians(w.phase)
        c, s = np.cos(theta), np.sin(theta)
        qa = w.steepness * w.amplitude
        y += w.amplitude * c
        x -= qa * dx * s
        z -= qa * dz * s
        qakc = qa * k * c
        aks = w.amplitude * k * s
        xx -= qakc * dx * dx
        xy -= aks * dx
        xz -= qakc * dx * dz
        zx -= qakc * dx * dz
        zy -= aks * dz
        zz -= qakc * dz * dz
    # n = dP/dz0 x dP/dx0 (= +y for a flat grid)
    n = np.stack([zy * xz - zz * xy, zz * xx - zx * xz, zx * xy - zy * xx], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.stack([x, y, z], axis=-1), n


def from_params(p) -> tuple[tuple[Wave, ...], list[str]]:
    """The waves a `water` generator's parameters describe (explicit `waves` tables, or the random
    set), and how error messages name each one."""
    tables = p.get("waves") or ()
    if tables:
        waves = tuple(Wave(**{k: float(v) for k, v in dict(t).items()}) for t in tables)
        return waves, [f"waves[{i}]" for i in range(len(waves))]
    waves = random_waves(int(p["wave_count"]), float(p["wavelength"]), float(p["amplitude"]),
                         float(p["direction"]), float(p["spread"]), float(p["steepness"]), int(p["seed"]))
    return waves, [f"wavelength: random wave {i} of {len(waves)}" for i in range(len(waves))]

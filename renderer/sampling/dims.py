"""Dimension ids of every decision a path makes, so that no two decisions share random numbers.

Camera: 0 (pixel jitter, 2D), 1 (lens, 2D). Bounce k uses BOUNCE_BASE + k * PER_BOUNCE + offset.
"""
PIXEL = 0
LENS = 1
BOUNCE_BASE = 2
PER_BOUNCE = 8
# offsets within a bounce
BSDF_LOBE = 0  # 1D
BSDF_DIRECTION = 1  # 2D
ROULETTE = 2  # 1D
LIGHT_SELECT = 3  # 1D
LIGHT_POINT = 4  # 2D
PHOTON = 5  # reserved for light paths (photon mapping)
SPARE = 6


def bounce(k: int, offset: int) -> int:
    """Python-side helper (kernels inline the same arithmetic)."""
    return BOUNCE_BASE + k * PER_BOUNCE + offset

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
MEDIUM_CHANNEL = 6  # 1D: the colour channel that picks the free-flight distance
MEDIUM_DISTANCE = 7  # 1D: the free-flight distance


# The wavelength of a spectral path (scenes with dispersive glass), drawn once per camera path
# when it first meets a dispersive surface: an id of its own, beyond every bounce's.
WAVELENGTH = 0x7000


def bounce(k: int, offset: int) -> int:
    """Python-side helper (kernels inline the same arithmetic)."""
    return BOUNCE_BASE + k * PER_BOUNCE + offset


# --- light paths (photons; `sppm`) ---------------------------------------------------------------
# Photons draw from their own sample stream (a photon index that runs on across iterations, and a
# stream key no pixel uses), and also from their own dimension ids, far above anything a camera
# path can reach (2 + 8 * 1024 ids, and +0x4000 for the second number of an independent 2D draw):
# no decision of a photon shares numbers with any camera decision or with another photon decision.
PHOTON_BASE = 0x8000
PHOTON_LIGHT_SELECT = PHOTON_BASE + 0  # 1D: which emitter (or the environment)
PHOTON_LIGHT_POINT = PHOTON_BASE + 1  # 2D: the point on the emitter (or the environment direction)
PHOTON_DIRECTION = PHOTON_BASE + 2  # 2D: the emitted direction (or the point on the environment's disc)
PHOTON_AIM = PHOTON_BASE + 3  # 1D: aimed at the target region or not
PHOTON_BOUNCE_BASE = PHOTON_BASE + 4
PHOTON_PER_BOUNCE = 4
# offsets within a photon bounce: BSDF_LOBE (1D), BSDF_DIRECTION (2D) and ROULETTE (1D), as above


def photon_bounce(k: int, offset: int) -> int:
    """Python-side helper: the id of decision `offset` at photon bounce k (0 = at the first hit)."""
    return PHOTON_BOUNCE_BASE + k * PHOTON_PER_BOUNCE + offset

"""Mitsuba media made into Lantern's MediumSpec: `homogeneous`, and `heterogeneous` with its volumes
(`gridvolume` from a .vol file, `constvolume`, or a plain value) for sigma_t and albedo.

Mitsuba's heterogeneous medium exists only inside its sigma_t volume's bounding box: the unit
cube its `to_world` places (the file's own box first, with `use_grid_bbox`), which for a constant
without a `to_world` is [0, 1]^3. The grid spec keeps exactly that cube, so a shape larger than
the box holds empty space around the medium, as in Mitsuba.
"""
from __future__ import annotations

import numpy as np

from renderer.scene.description import MediumSpec, VolumeGridSpec
from renderer.scene.mitsuba.plugins import Plugin
from renderer.scene.mitsuba.scene_warnings import leave_out, warn
from renderer.scene.vol_files import read_vol

DEFAULT_SIGMA_T = 1.0  # Mitsuba's media
DEFAULT_ALBEDO = 0.75
FILTERS = {"trilinear": False, "nearest": True}  # gridvolume filter_type -> nearest


def medium_spec(builder, medium: Plugin, name: str) -> MediumSpec | None:
    """The medium `name` of a <medium> plugin, or None (with a warning) for a kind Lantern lacks."""
    if medium.type not in ("homogeneous", "heterogeneous"):
        leave_out(medium, "only homogeneous and heterogeneous media are supported: the shape is empty inside")
        return None
    g = _phase_g(builder, medium)
    medium.used.add("sample_emitters")
    scale = medium.number("scale", 1.0)
    if scale < 0.0:
        raise medium.error(f"scale {scale:g} is negative")
    if medium.type == "heterogeneous":
        medium.used.add("has_spectral_extinction")
        density = _volume(builder, medium, "sigma_t", DEFAULT_SIGMA_T, bounded=False)
        if np.min(density.values) < 0.0:
            raise medium.error(f"sigma_t{_from(density)} holds negative values")
        albedo = _volume(builder, medium, "albedo", DEFAULT_ALBEDO, bounded=True)
        return MediumSpec(name, sigma_s=(0.0, 0.0, 0.0), g=g, kind="grid", density=density, albedo=albedo,
                          scale=scale)
    sigma_t = np.array(builder.colour(medium, "sigma_t", (DEFAULT_SIGMA_T,) * 3, bounded=False)) * scale
    albedo = np.array(builder.colour(medium, "albedo", (DEFAULT_ALBEDO,) * 3))
    return MediumSpec(name, sigma_a=_vec(sigma_t * (1.0 - albedo)), sigma_s=_vec(sigma_t * albedo), g=g)


def _phase_g(builder, medium: Plugin) -> float:
    phases = medium.objects("phase")
    if not phases:
        return 0.0
    phase = builder.visit(phases[0])
    if phase.type == "hg":
        return phase.number("g", 0.8)
    if phase.type != "isotropic":
        warn(phase, "rendered as an isotropic phase function")
    return 0.0


def _volume(builder, medium: Plugin, name: str, default: float, bounded: bool) -> VolumeGridSpec:
    """A heterogeneous medium's parameter as a grid: a <volume>, or a value (a constant over
    Mitsuba's default box, the unit cube)."""
    value = medium.properties.get(name)
    if not (isinstance(value, Plugin) and value.kind == "volume"):
        return _constant(builder.colour(medium, name, (default,) * 3, bounded=bounded), np.eye(4))
    medium.used.add(name)
    volume = builder.visit(value)
    if volume.type == "gridvolume":
        return _grid(builder, volume)
    if volume.type == "constvolume":
        return _constant(builder.colour(volume, "value", (1.0,) * 3, bounded=bounded), _placement(volume))
    leave_out(volume, f"this volume type is not supported: '{name}' is {default:g} everywhere in the unit cube")
    return _constant((default,) * 3, np.eye(4))


def _grid(builder, volume: Plugin) -> VolumeGridSpec:
    filename = volume.text("filename")
    if filename is None:
        raise volume.error("needs a filename (a Mitsuba .vol grid)")
    path = builder.find(volume, filename)
    grid = read_vol(path, builder.model_files.ledger)  # (a checkpoint's fingerprint covers it: spec.file)
    to_world = _placement(volume)
    if volume.get("use_grid_bbox", False):
        lo, hi = (np.array(corner) for corner in grid.bounds)
        box = np.diag([*(hi - lo), 1.0])
        box[:3, 3] = lo
        to_world = to_world @ box
        _check_invertible(volume, to_world, "its to_world with the file's bounding box")
    filter_type = volume.text("filter_type", "trilinear")
    if filter_type not in FILTERS:
        raise volume.error(f"filter_type '{filter_type}' (trilinear or nearest)")
    wrap = volume.text("wrap_mode", "clamp")
    if wrap != "clamp":
        warn(volume, f"wrap_mode '{wrap}' is rendered as clamp")
    volume.used.update(("raw", "accel"))  # spectral upsampling and the lookup's acceleration: RGB the same
    return VolumeGridSpec(grid.values, to_world=_rows(to_world), nearest=FILTERS[filter_type], file=path)


def _placement(volume: Plugin) -> np.ndarray:
    to_world = volume.transform()
    _check_invertible(volume, to_world, "its to_world")
    return to_world


def _check_invertible(volume: Plugin, matrix: np.ndarray, what: str) -> None:
    if abs(np.linalg.det(matrix[:3, :3])) < 1e-30:
        raise volume.error(f"{what} is singular: the volume has no inside")


def _constant(colour, to_world: np.ndarray) -> VolumeGridSpec:
    rgb = tuple(float(c) for c in colour)
    return VolumeGridSpec(np.array(rgb, np.float32).reshape(1, 1, 1, 3), to_world=_rows(to_world), constant=rgb)


def _from(spec: VolumeGridSpec) -> str:
    return f" ({spec.file.name})" if spec.file is not None else ""


def _rows(matrix: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(x) for x in row) for row in matrix)


def _vec(v) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))

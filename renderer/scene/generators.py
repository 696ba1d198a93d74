"""Procedural meshes for `type = "generated"` objects of mesh scenes.

`generate(generator, params)` returns `(positions, indices, normals)` in the object's local frame:
positions (V, 3) float32 metres, indices (T, 3) int32 counter-clockwise seen from the front
(outside), normals (V, 3) float32 unit length. The caller applies the object's transform.

Everything is vectorised numpy and deterministic: the same parameters give bit-identical arrays.
Parameter names, defaults and ranges are those of `renderer.scene.schema.GENERATORS` (the scene
loader has validated them); missing parameters take the schema's defaults.

terrain
    A (resolution + 1)^2 grid of vertices over [-size/2, size/2]^2 in the xz plane (2 triangles
    per grid cell, so resolution 708 gives 1,002,528 triangles). Heights are fractal value noise:
    `TERRAIN_OCTAVES` octaves of smoothly interpolated random lattice values in [-1, 1] (drawn
    from `numpy.random.default_rng(seed)`), the lattice doubling in density and the amplitude
    halving per octave, normalised by the sum of the amplitudes and multiplied by `height`, so
    every height lies in [-height, height]. Normals come from central differences of the height
    field (one-sided at the border): n ~ (-dh/dx, 1, -dh/dz). Every triangle has a positive
    area (its projection on the xz plane is half a grid cell), so none is degenerate.
icosphere
    `trimesh.creation.icosphere(subdivisions, radius)`: 20 * 4^subdivisions triangles, vertices
    exactly on the sphere; normals = positions / radius.
light_panels
    `count_x` x `count_z` small square panels (`panel_size` on a side, 2 triangles and 4 vertices
    each, none shared) in the plane y = `height`, facing down (-y: their front side, which is the
    emitting side of a one-sided emitter). Panel (i, j) sits at the centre of cell (i, j) of a
    `size` x `size` square centred on the y axis (cells `size / count` wide), moved by a seeded
    jitter, uniform within +-1/4 of the gap between panel and cell on each axis, so panels never
    leave their cells and never overlap unless `panel_size` exceeds the cell. Panels are listed
    row by row (z, then x); panel k holds triangles 2k and 2k + 1. Meant as many small emitters
    (with an emissive material) for many-light sampling: the defaults give 10,000 panels,
    20,000 triangles.
water
    A (resolution + 1)^2 grid over [-size/2, size/2]^2 in the xz plane (the terrain's vertex order
    and triangles), each vertex displaced by a sum of Gerstner waves and given the surface's
    analytic normal (`renderer.scene.waves`: formulas, conventions and why the checks suffice).
    The waves are the `waves` tables or a random set from `seed`. Parameters that would alias
    (a wave shorter than two cells) or loop (steepness sum >= 1) raise ValueError; with them
    refused, the displaced grid has no folded or degenerate triangle and every normal has n.y > 0.
cylinder, disc_fan, cube
    Shapes with texture coordinates (renderer/scene/shape_meshes.py: what each is). `generated_mesh`
    keeps their texture coordinates; `generate` returns the three arrays every generator has.
"""
from __future__ import annotations

from typing import Mapping, Union

import numpy as np

from renderer.scene import schema, shape_meshes, waves
from renderer.scene.mesh_model import TriangleMesh

SHAPES_WITH_UVS = ("cylinder", "disc_fan", "cube")
TERRAIN_OCTAVES = 6
TERRAIN_BASE_CELLS = 4  # lattice cells along each side at the first (coarsest) octave

Params = Union[Mapping[str, object], tuple]


def _params(generator: str, params: Params) -> dict:
    spec = schema.GENERATORS_BY_NAME.get(generator)
    if spec is None:
        raise ValueError(f"unknown generator '{generator}' (known: {', '.join(schema.GENERATORS_BY_NAME)})")
    given = dict(params)
    known = {f.name: f.default for f in spec.params}
    unknown = sorted(set(given) - set(known))
    if unknown:
        raise ValueError(f"generator '{generator}' has no parameter {', '.join(unknown)} "
                         f"(known: {', '.join(known)})")
    return {**known, **given}


def triangle_count(generator: str, params: Params = ()) -> int:
    """How many triangles `generate` makes, without making them."""
    p = _params(generator, params)
    if generator == "terrain":
        return 2 * int(p["resolution"]) ** 2
    if generator == "light_panels":
        return 2 * int(p["count_x"]) * int(p["count_z"])
    if generator == "water":
        return 2 * int(p["resolution"]) ** 2
    if generator == "cylinder":
        return 2 * int(p["sectors"])
    if generator == "disc_fan":
        return int(p["sectors"])
    if generator == "cube":
        return 12
    return 20 * 4 ** int(p["subdivisions"])


def generate(generator: str, params: Params = ()) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(positions (V,3) float32, indices (T,3) int32, normals (V,3) float32), local frame."""
    p = _params(generator, params)
    if generator == "terrain":
        return terrain(int(p["resolution"]), float(p["size"]), float(p["height"]), int(p["seed"]))
    if generator == "light_panels":
        return light_panels(int(p["count_x"]), int(p["count_z"]), float(p["size"]),
                            float(p["panel_size"]), float(p["height"]), int(p["seed"]))
    if generator == "water":
        wave_set, names = waves.from_params(p)
        return water(int(p["resolution"]), float(p["size"]), wave_set, names)
    if generator in SHAPES_WITH_UVS:
        return _shape_with_uvs(generator, p)[:3]
    return icosphere(int(p["subdivisions"]), float(p["radius"]))


def generated_mesh(generator: str, params: Params = ()) -> TriangleMesh:
    """The generator's mesh as a TriangleMesh, with texture coordinates where it has them."""
    if generator in SHAPES_WITH_UVS:
        positions, indices, normals, uvs = _shape_with_uvs(generator, _params(generator, params))
        return TriangleMesh(positions, indices, normals=normals, uv0=uvs)
    positions, indices, normals = generate(generator, params)
    return TriangleMesh(positions, indices, normals=normals)


def _shape_with_uvs(generator: str, p: dict):
    if generator == "cylinder":
        return shape_meshes.cylinder(float(p["radius"]), float(p["height"]), int(p["sectors"]))
    if generator == "disc_fan":
        return shape_meshes.disc_fan(float(p["radius"]), int(p["sectors"]))
    return shape_meshes.cube(float(p["size"]))


# --- terrain ---------------------------------------------------------------------------------


def _smoothstep(t: np.ndarray) -> np.ndarray:
    return t * t * (3.0 - 2.0 * t)


def value_noise(samples: int, seed: int, octaves: int = TERRAIN_OCTAVES,
                base_cells: int = TERRAIN_BASE_CELLS) -> np.ndarray:
    """Fractal value noise on a samples x samples grid covering the unit square, in [-1, 1].

    Each octave is a lattice of uniform random values, interpolated with smoothstep weights
    separably (along x for every lattice row, then along z): O(samples^2) per octave.
    """
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, samples)
    total = np.zeros((samples, samples), dtype=np.float64)
    amplitude, norm = 1.0, 0.0
    for octave in range(octaves):
        cells = base_cells << octave
        lattice = rng.uniform(-1.0, 1.0, size=(cells + 1, cells + 1))
        u = t * cells
        i0 = np.minimum(u.astype(np.int64), cells - 1)  # the last sample sits in the last cell
        w = _smoothstep(u - i0)
        along_x = lattice[:, i0] * (1.0 - w) + lattice[:, i0 + 1] * w  # (cells + 1, samples)
        layer = along_x[i0, :] * (1.0 - w)[:, None] + along_x[i0 + 1, :] * w[:, None]
        total += amplitude * layer
        norm += amplitude
        amplitude *= 0.5
    return total / norm


def grid_indices(resolution: int) -> np.ndarray:
    """Two counter-clockwise (seen from +y) triangles per cell of a vertex grid whose row i
    (z index) and column j (x index) vertex is i * (resolution + 1) + j."""
    n = resolution + 1
    j, i = np.meshgrid(np.arange(resolution, dtype=np.int32), np.arange(resolution, dtype=np.int32))
    v00 = (i * n + j).ravel()
    v01 = v00 + 1  # +x
    v10 = v00 + n  # +z
    v11 = v10 + 1
    tris = np.empty((resolution * resolution, 2, 3), dtype=np.int32)
    # (v00, v10, v01): (p10 - p00) x (p01 - p00) = (0, 0, dz) x (dx, 0, 0) = (0, dz dx, 0): up.
    tris[:, 0, 0], tris[:, 0, 1], tris[:, 0, 2] = v00, v10, v01
    tris[:, 1, 0], tris[:, 1, 1], tris[:, 1, 2] = v01, v10, v11
    return tris.reshape(-1, 3)


def terrain(resolution: int = 708, size: float = 10.0, height: float = 1.0,
            seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if resolution < 2:
        raise ValueError("terrain resolution must be at least 2")
    n = resolution + 1
    coords = np.linspace(-0.5 * size, 0.5 * size, n)
    h = value_noise(n, seed) * height  # h[i, j]: row i is z, column j is x
    positions = np.empty((n, n, 3), dtype=np.float32)
    positions[:, :, 0] = coords[None, :]
    positions[:, :, 1] = h
    positions[:, :, 2] = coords[:, None]
    spacing = size / resolution
    dh_dz, dh_dx = np.gradient(h, spacing)
    normals = np.empty((n, n, 3), dtype=np.float64)
    normals[:, :, 0] = -dh_dx
    normals[:, :, 1] = 1.0
    normals[:, :, 2] = -dh_dz
    normals /= np.sqrt(np.einsum("ijk,ijk->ij", normals, normals))[:, :, None]
    return (positions.reshape(-1, 3), grid_indices(resolution),
            normals.astype(np.float32).reshape(-1, 3))


# --- icosphere -------------------------------------------------------------------------------


def icosphere(subdivisions: int = 3, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    import trimesh  # imported here: only this generator needs it

    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    normals = vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    return (np.ascontiguousarray(vertices, dtype=np.float32),
            np.ascontiguousarray(mesh.faces, dtype=np.int32),
            np.ascontiguousarray(normals, dtype=np.float32))


# --- light_panels ----------------------------------------------------------------------------


def light_panels(count_x: int = 100, count_z: int = 100, size: float = 20.0,
                 panel_size: float = 0.05, height: float = 3.0,
                 seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if count_x < 1 or count_z < 1:
        raise ValueError("light_panels counts must be at least 1")
    if not (size > 0 and panel_size > 0):
        raise ValueError("light_panels size and panel_size must be positive")
    cell_x, cell_z = size / count_x, size / count_z
    rng = np.random.default_rng(seed)
    jitter = rng.uniform(-1.0, 1.0, size=(count_z, count_x, 2))
    jitter[..., 0] *= 0.25 * max(cell_x - panel_size, 0.0)
    jitter[..., 1] *= 0.25 * max(cell_z - panel_size, 0.0)
    x = -0.5 * size + (np.arange(count_x) + 0.5) * cell_x  # cell centres
    z = -0.5 * size + (np.arange(count_z) + 0.5) * cell_z
    cx = (x[None, :] + jitter[..., 0]).ravel()  # panel k = j * count_x + i
    cz = (z[:, None] + jitter[..., 1]).ravel()
    half = 0.5 * panel_size
    n = cx.shape[0]
    positions = np.empty((n, 4, 3), dtype=np.float64)
    # corners 0: (-x, -z), 1: (+x, -z), 2: (-x, +z), 3: (+x, +z)
    positions[:, :, 0] = cx[:, None] + np.array([-half, half, -half, half])
    positions[:, :, 1] = height
    positions[:, :, 2] = cz[:, None] + np.array([-half, -half, half, half])
    # (c0, c1, c2): (c1 - c0) x (c2 - c0) = (s, 0, 0) x (0, 0, s) = (0, -s^2, 0): facing -y;
    # (c1, c3, c2) likewise.
    corners = np.array([[0, 1, 2], [1, 3, 2]], dtype=np.int32)
    indices = (np.arange(n, dtype=np.int32)[:, None, None] * 4 + corners[None]).reshape(-1, 3)
    normals = np.tile(np.float32([0.0, -1.0, 0.0]), (4 * n, 1))
    return (positions.astype(np.float32).reshape(-1, 3), np.ascontiguousarray(indices), normals)


# --- water -----------------------------------------------------------------------------------


def water(resolution: int = 256, size: float = 4.0, wave_set=(), names=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A Gerstner-wave surface over a (resolution + 1)^2 grid; see `renderer.scene.waves`."""
    if resolution < 2 or not size > 0.0:
        raise ValueError("water resolution must be at least 2 and size positive")
    problem = waves.problems(tuple(wave_set), size / resolution, names)
    if problem:
        raise ValueError(problem)
    n = resolution + 1
    coords = np.linspace(-0.5 * size, 0.5 * size, n)
    positions, normals = waves.surface(wave_set, coords[None, :], coords[:, None])  # row i is z
    return (np.ascontiguousarray(positions.reshape(-1, 3), dtype=np.float32), grid_indices(resolution),
            np.ascontiguousarray(normals.reshape(-1, 3), dtype=np.float32))

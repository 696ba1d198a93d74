"""Write assets/models/textured_sphere.glb: a textured sphere on a tiled floor, as one GLB file.

Every texture is procedural and the file is written by the project's glTF writer
(renderer/scene/model_formats/gltf_writing.py: buffer, accessors, PNGs, the GLB container), so the
asset can be rebuilt anywhere the project runs:

    .venv/bin/python scripts/make_textured_gltf.py [output.glb]

Contents (glTF 2.0, metres, y up):

- node "sphere": a UV sphere (radius SPHERE_RADIUS, SEGMENTS x RINGS quads, seam and pole
  vertices duplicated so UVs are continuous) translated to SPHERE_CENTER. Material "tiles":
  base colour = an orange and cream checker (sRGB PNG); metallic-roughness = roughness (G)
  rising from smooth at the top of the image to rough at the bottom, metallic (B) in vertical
  stripes; a tangent-space normal map of bevelled tiles. Sampler: wrap S REPEAT (around the
  sphere), wrap T CLAMP_TO_EDGE (pole to pole).
- node "floor": a FLOOR_SIZE x FLOOR_SIZE quad at y = 0 facing +y. Material "floor": grey tiles
  with dark grout (base colour), rough grout and smoother tiles (G), not metallic (B = 0 and
  metallicFactor 0), and the same tile normal map at a lower strength. Every texture of the floor
  carries KHR_texture_transform scale FLOOR_UV_SCALE (the floor shows the pattern that many times
  across), with a REPEAT / REPEAT sampler.

Both meshes carry POSITION, NORMAL, TEXCOORD_0 and TANGENT (xyz, w) per glTF: the bitangent
w * cross(N, T) points up in the image (towards decreasing v), the +y of the normal map.
The arrays and images are exposed as functions so that tests can compare the loaded file with
what this script wrote.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from renderer.scene.model_formats.gltf_writing import BufferBuilder, glb_bytes, png_bytes

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "assets" / "models" / "textured_sphere.glb"

SPHERE_RADIUS = 1.0
SPHERE_CENTER = (0.0, 1.0, 0.0)
SEGMENTS, RINGS = 64, 32  # quads around the equator and from pole to pole
FLOOR_SIZE = 8.0
FLOOR_UV_SCALE = (4.0, 4.0)
TEX = 256  # texture edge length, pixels
TILES = 8  # checker / tile cells along each image edge
SPHERE_NORMAL_SCALE = 1.0
FLOOR_NORMAL_SCALE = 0.6

# glTF enums
LINEAR, LINEAR_MIPMAP_LINEAR = 9729, 9987
REPEAT, CLAMP_TO_EDGE = 10497, 33071

SPHERE_SAMPLER = {"magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR,
                  "wrapS": REPEAT, "wrapT": CLAMP_TO_EDGE}
FLOOR_SAMPLER = {"magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR,
                 "wrapS": REPEAT, "wrapT": REPEAT}

SPHERE_MATERIAL_FACTORS = {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 1.0,
                           "roughnessFactor": 1.0}
FLOOR_MATERIAL_FACTORS = {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
                          "roughnessFactor": 1.0}


# --- meshes ----------------------------------------------------------------------------------


def sphere_mesh() -> dict[str, np.ndarray]:
    """UV sphere in its own frame (the node adds SPHERE_CENTER).

    u = phi / 2pi runs around +y, v = theta / pi from the north pole (v = 0, the top of the image)
    to the south pole. Position = r (sin t cos p, cos t, -sin t sin p): seen from above, u grows
    counter-clockwise, which with v growing downwards makes every triangle below counter-clockwise
    seen from outside.
    """
    u = np.linspace(0.0, 1.0, SEGMENTS + 1)
    v = np.linspace(0.0, 1.0, RINGS + 1)
    uu, vv = np.meshgrid(u, v)  # (RINGS + 1, SEGMENTS + 1)
    phi, theta = 2.0 * np.pi * uu, np.pi * vv
    normal = np.stack([np.sin(theta) * np.cos(phi), np.cos(theta), -np.sin(theta) * np.sin(phi)], -1)
    # d(position)/du without the sin(theta) factor, so that it stays defined at the poles.
    tangent = np.stack([-np.sin(phi), np.zeros_like(phi), -np.cos(phi)], -1)
    # Bitangent must be -d(position)/dv (image up) = -pi r (cos t cos p, -sin t, -cos t sin p);
    # cross(N, T) has the same direction here, so w = +1 (checked in `check_frames`).
    w = np.ones(phi.shape + (1,))
    n = SEGMENTS + 1
    i, j = np.meshgrid(np.arange(RINGS), np.arange(SEGMENTS), indexing="ij")
    a = (i * n + j).ravel()
    b, c, d = a + n, a + n + 1, a + 1  # a: (i, j), b: (i + 1, j), c: (i + 1, j + 1), d: (i, j + 1)
    quads = np.stack([a, b, c, a, c, d], -1).reshape(-1, 2, 3)
    # The first ring's (a, c, d) and the last ring's (a, b, c) collapse onto a pole: drop them.
    keep = np.ones(quads.shape[:2], dtype=bool)
    keep[: SEGMENTS, 1] = False
    keep[-SEGMENTS:, 0] = False
    indices = quads[keep].astype(np.uint32)
    return {
        "positions": (SPHERE_RADIUS * normal).reshape(-1, 3).astype(np.float32),
        "normals": normal.reshape(-1, 3).astype(np.float32),
        "tangents": np.concatenate([tangent, w], -1).reshape(-1, 4).astype(np.float32),
        "uvs": np.stack([uu, vv], -1).reshape(-1, 2).astype(np.float32),
        "indices": indices,
    }


def floor_mesh() -> dict[str, np.ndarray]:
    """A quad at y = 0 facing +y; u along +x, v along +z (the image's top row at -z)."""
    h = FLOOR_SIZE / 2.0
    positions = np.array([[-h, 0, -h], [h, 0, -h], [h, 0, h], [-h, 0, h]], dtype=np.float32)
    return {
        "positions": positions,
        "normals": np.tile(np.array([0, 1, 0], np.float32), (4, 1)),
        # T = +x; image up (-v) is -z = cross(+y, +x): w = +1.
        "tangents": np.tile(np.array([1, 0, 0, 1], np.float32), (4, 1)),
        "uvs": np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float32),
        "indices": np.array([[0, 2, 1], [0, 3, 2]], dtype=np.uint32),
    }


def check_frames(mesh: dict[str, np.ndarray]) -> None:
    """Winding (counter-clockwise seen from the normal side) and tangent handedness."""
    p, tri = mesh["positions"].astype(np.float64), mesh["indices"]
    face = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    assert np.all(np.einsum("ij,ij->i", face, mesh["normals"][tri].sum(1)) > 0), "winding"
    uv = mesh["uvs"].astype(np.float64)
    duv1, duv2 = uv[tri[:, 1]] - uv[tri[:, 0]], uv[tri[:, 2]] - uv[tri[:, 0]]
    e1, e2 = p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]
    det = duv1[:, 0] * duv2[:, 1] - duv2[:, 0] * duv1[:, 1]
    dp_dv = (duv1[:, 0:1] * e2 - duv2[:, 0:1] * e1) / det[:, None]
    t = mesh["tangents"][tri[:, 0]]
    n = mesh["normals"][tri[:, 0]]
    bitangent = t[:, 3:4] * np.cross(n, t[:, :3])
    assert np.all(np.einsum("ij,ij->i", bitangent, -dp_dv) > 0), "tangent handedness"


# --- textures (uint8 RGB, row 0 = top of the image = v 0) ------------------------------------


def _cells() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per pixel: tile row, tile column, distance in pixels to the nearest tile edge."""
    cell = TEX // TILES
    rows, cols = np.mgrid[0:TEX, 0:TEX]
    fr, fc = rows % cell + 0.5, cols % cell + 0.5
    edge = np.minimum(np.minimum(fr, cell - fr), np.minimum(fc, cell - fc))
    return rows // cell, cols // cell, edge


def sphere_base_color() -> np.ndarray:
    tr, tc, _ = _cells()
    orange, cream = np.array([222, 110, 38]), np.array([238, 228, 205])
    return np.where(((tr + tc) % 2 == 0)[..., None], orange, cream).astype(np.uint8)


def sphere_metallic_roughness() -> np.ndarray:
    rows, cols = np.mgrid[0:TEX, 0:TEX]
    out = np.empty((TEX, TEX, 3), dtype=np.uint8)
    out[..., 0] = 255  # occlusion slot: unused
    out[..., 1] = np.round(20 + 215 * rows / (TEX - 1)).astype(np.uint8)  # roughness ~0.08 .. 0.92
    out[..., 2] = np.where((cols // (TEX // (2 * TILES))) % 2 == 0, 255, 0)  # metallic stripes
    return out


def tile_normal_map(bevel: float = 5.0, strength: float = 2.0) -> np.ndarray:
    """Bevelled tiles: height 1 on a tile, falling to 0 over `bevel` pixels at its edges.

    Tangent space: +x is +u (right), +y is image up (decreasing row), +z out of the surface.
    Differences wrap around, so the map tiles seamlessly.
    """
    _, _, edge = _cells()
    s = np.clip(edge / bevel, 0.0, 1.0)
    height = s * s * (3.0 - 2.0 * s)
    dh_dcol = (np.roll(height, -1, axis=1) - np.roll(height, 1, axis=1)) / 2.0
    dh_drow = (np.roll(height, -1, axis=0) - np.roll(height, 1, axis=0)) / 2.0
    # height gradient along +y (up) is -dh_drow; n ~ (-dh/dx, -dh/dy, 1).
    n = np.stack([-strength * dh_dcol, strength * dh_drow, np.ones_like(height)], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.round((n * 0.5 + 0.5) * 255.0).astype(np.uint8)


def floor_base_color() -> np.ndarray:
    tr, tc, edge = _cells()
    # A fixed per-tile brightness variation (a small integer hash of the tile position).
    shade = ((tr * 7 + tc * 13) % 5).astype(np.float64) * 6.0
    tile = np.stack([150 + shade, 148 + shade, 142 + shade], -1)
    grout = np.array([60.0, 56.0, 52.0])
    return np.where((edge < 2.0)[..., None], grout, tile).astype(np.uint8)


def floor_metallic_roughness() -> np.ndarray:
    _, _, edge = _cells()
    out = np.zeros((TEX, TEX, 3), dtype=np.uint8)
    out[..., 0] = 255
    out[..., 1] = np.where(edge < 2.0, 230, 90)  # grout rough (0.9), tiles ~0.35
    out[..., 2] = 0  # not metallic
    return out


IMAGES = (  # (name, function, colour data in sRGB?)
    ("sphere_base_color.png", sphere_base_color, True),
    ("sphere_metallic_roughness.png", sphere_metallic_roughness, False),
    ("tile_normal.png", tile_normal_map, False),
    ("floor_base_color.png", floor_base_color, True),
    ("floor_metallic_roughness.png", floor_metallic_roughness, False),
)


# --- the glTF document -----------------------------------------------------------------------


def _primitive(buf: BufferBuilder, mesh: dict[str, np.ndarray], material: int) -> dict:
    return {"attributes": {"POSITION": buf.accessor(mesh["positions"], bounds=True),
                           "NORMAL": buf.accessor(mesh["normals"], bounds=False),
                           "TANGENT": buf.accessor(mesh["tangents"]),
                           "TEXCOORD_0": buf.accessor(mesh["uvs"])},
            "indices": buf.accessor(mesh["indices"].reshape(-1)), "material": material, "mode": 4}


def _texture_info(texture: int, transform: bool, **extra) -> dict:
    info = {"index": texture, **extra}
    if transform:
        info["extensions"] = {"KHR_texture_transform": {"scale": list(FLOOR_UV_SCALE)}}
    return info


def build() -> tuple[dict, bytes]:
    sphere, floor = sphere_mesh(), floor_mesh()
    check_frames(sphere)
    check_frames(floor)
    buf = BufferBuilder()
    meshes = [{"name": "sphere", "primitives": [_primitive(buf, sphere, 0)]},
              {"name": "floor", "primitives": [_primitive(buf, floor, 1)]}]
    images = [{"name": name, "mimeType": "image/png", "bufferView": buf.view(png_bytes(make(), optimize=True))}
              for name, make, _ in IMAGES]
    # textures: 0-2 sphere (sampler 0), 3-5 floor (sampler 1); the normal map image is shared.
    textures = [{"sampler": 0, "source": 0}, {"sampler": 0, "source": 1}, {"sampler": 0, "source": 2},
                {"sampler": 1, "source": 3}, {"sampler": 1, "source": 4}, {"sampler": 1, "source": 2}]
    materials = [
        {"name": "tiles",
         "pbrMetallicRoughness": {**SPHERE_MATERIAL_FACTORS,
                                  "baseColorTexture": _texture_info(0, False),
                                  "metallicRoughnessTexture": _texture_info(1, False)},
         "normalTexture": _texture_info(2, False, scale=SPHERE_NORMAL_SCALE)},
        {"name": "floor",
         "pbrMetallicRoughness": {**FLOOR_MATERIAL_FACTORS,
                                  "baseColorTexture": _texture_info(3, True),
                                  "metallicRoughnessTexture": _texture_info(4, True)},
         "normalTexture": _texture_info(5, True, scale=FLOOR_NORMAL_SCALE)},
    ]
    doc = {
        "asset": {"version": "2.0", "generator": "Lantern scripts/make_textured_gltf.py",
                  "copyright": "CC0"},
        "extensionsUsed": ["KHR_texture_transform"],
        "scene": 0,
        "scenes": [{"name": "textured", "nodes": [0, 1]}],
        "nodes": [{"name": "sphere", "mesh": 0, "translation": list(SPHERE_CENTER)},
                  {"name": "floor", "mesh": 1}],
        "meshes": meshes,
        "materials": materials,
        "textures": textures,
        "samplers": [SPHERE_SAMPLER, FLOOR_SAMPLER],
        "images": images,
        "accessors": buf.accessors,
        "bufferViews": buf.views,
        "buffers": [{"byteLength": len(buf.data)}],
    }
    return doc, bytes(buf.data)


def main(argv: list[str]) -> int:
    out = Path(argv[1]) if len(argv) > 1 else OUT
    data = glb_bytes(*build())
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_bytes(data)
    print(f"wrote {out} ({len(data) / 1024:.0f} KiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

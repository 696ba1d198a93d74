"""Write the small models the mesh-loader tests read. Run from anywhere:

    python tests/data/make_test_models.py

Everything is generated from the numbers below (no binary is hand-edited), so the tests can
compare what the loader returns with these exact values. Outputs, next to this script:

- textured_quad.gltf + textured_quad.bin + checker.png, mr.png, normal.png:
  one quad with NORMAL, TEXCOORD_0, TEXCOORD_1 (no TANGENT) and a material using every texture
  slot, two samplers, KHR_texture_transform, KHR_materials_emissive_strength,
  KHR_materials_transmission and KHR_materials_ior; a second material samples mr.png as colour.
- textured_quad.glb: the same model as one binary file (buffer and images embedded).
- two_nodes.gltf: a node hierarchy with TRS and matrix transforms, non-uniform scale, one mesh
  instanced by two nodes, a mirrored node, a triangle strip, a primitive without a material,
  TANGENT and normalized COLOR_0 attributes and a sparse accessor; the buffer is a data URI.
- materials.obj + materials.mtl: four OBJ material groups (textured with -o/-s, glass, lamp, mirror).
- pyramid.ply: ASCII PLY, triangles and a quad, vertex normals and 8-bit vertex colours.
- alpha_colors.gltf + alpha.png: alphaMode MASK and BLEND materials sharing an RGBA base-colour
  texture with a varying alpha; three primitives with COLOR_0 as float VEC3, normalized u8 VEC4
  and normalized u16 VEC4.
- instancing.gltf: a mesh placed by two nodes (one of them mirroring), and a node under a parent
  with EXT_mesh_gpu_instancing (TRANSLATION, normalized-short ROTATION, SCALE; one instance
  mirrored); a mesh placed once stays in world space.
- layers.gltf + layer.png + rgb16.png (16 bits per channel): one material per layer extension
  (KHR_materials_clearcoat, _sheen, _specular, _volume with transmission), each factor and
  texture slot set, and a transmissive material without a volume (thin-walled).
- imperfect.gltf: a texture whose file is missing, and extensionsUsed that the loader does not
  implement (KHR_materials_unlit, KHR_lights_punctual; not required).
- cutout.gltf + cutout.png: a 2 m black quad facing +z whose base-colour alpha is a 4 x 4
  checker of 0 and 1 (clamped at the edges), alphaMode MASK: the renderer's coverage tests.
- colored_quads.gltf: three 2 m quads facing +z side by side: COLOR_0 linear in position on an
  opaque material, COLOR_0 whose alpha runs from 0 to 1 across a MASK material, and no COLOR_0.
- simple_instancing.gltf: a stand-in for Khronos' SimpleInstancing sample: one cube drawn 64
  times by EXT_mesh_gpu_instancing (translations on a 4 x 4 x 4 grid, rotations, scales).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from renderer.scene.model_formats.gltf_writing import (
    BufferBuilder,
    data_uri_buffer,
    glb_bytes,
    png16_bytes,
    png_bytes,
)

HERE = Path(__file__).resolve().parent

# --- images (8-bit, so the loader's k / 255 decoding is exact) ---------------------------------

CHECKER = np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]],
                    [[0, 0, 0], [128, 128, 128], [64, 32, 16], [200, 100, 50]],
                    [[10, 20, 30], [40, 50, 60], [70, 80, 90], [100, 110, 120]],
                    [[255, 255, 0], [0, 255, 255], [255, 0, 255], [1, 2, 3]]], dtype=np.uint8)
MR = np.array([[[0, 64, 255], [0, 128, 0]],
               [[0, 255, 128], [0, 32, 64]]], dtype=np.uint8)  # G = roughness, B = metallic
NORMAL = np.array([[[128, 128, 255], [160, 128, 240]],
                   [[128, 96, 240], [100, 150, 230]]], dtype=np.uint8)
ALPHA = np.array([[[255, 0, 0, 0], [0, 255, 0, 64]],
                  [[0, 0, 255, 128], [255, 255, 255, 255]]], dtype=np.uint8)  # RGBA, alpha varies
LAYER = np.array([[[10, 60, 110, 160], [20, 70, 120, 170]],
                  [[30, 80, 130, 180], [40, 90, 140, 190]]], dtype=np.uint8)  # RGBA, every channel distinct
RGB16 = np.array([[[0, 1, 65535], [1000, 30000, 50000]],
                  [[65534, 257, 12345], [40000, 20000, 100]]], dtype=np.uint16)  # needs 16 bits

# --- textured quad ----------------------------------------------------------------------------

QUAD_POSITIONS = np.array([[-1, 1, 0], [1, 1, 0], [1, -1, 0], [-1, -1, 0]], dtype=np.float32)
QUAD_NORMALS = np.array([[0, 0, 1]] * 4, dtype=np.float32)
QUAD_UV0 = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float32)  # (0, 0) = top-left
QUAD_UV1 = QUAD_UV0 * np.float32(2.0)
QUAD_INDICES = np.array([0, 3, 2, 0, 2, 1], dtype=np.uint16)  # counter-clockwise seen from +z
QUAD_TRANSLATION = [0.5, 0.0, 0.0]

QUAD_MATERIAL = {
    "name": "quad",
    "pbrMetallicRoughness": {
        "baseColorFactor": [0.9, 0.8, 0.7, 1.0],
        "metallicFactor": 0.25,
        "roughnessFactor": 0.625,
        "baseColorTexture": {
            "index": 0,
            "texCoord": 0,
            "extensions": {"KHR_texture_transform": {
                "offset": [0.25, 0.5], "rotation": 0.5, "scale": [2.0, 3.0]}},
        },
        "metallicRoughnessTexture": {"index": 1, "texCoord": 1},
    },
    "normalTexture": {"index": 2, "scale": 0.75},
    "occlusionTexture": {"index": 1},  # ignored by design
    "emissiveTexture": {"index": 0},
    "emissiveFactor": [1.0, 0.5, 0.25],
    "alphaMode": "MASK",
    "alphaCutoff": 0.25,
    "doubleSided": True,
    "extensions": {
        "KHR_materials_emissive_strength": {"emissiveStrength": 4.0},
        "KHR_materials_transmission": {"transmissionFactor": 0.375},
        "KHR_materials_ior": {"ior": 1.33},
    },
}
SECOND_MATERIAL = {"name": "second", "pbrMetallicRoughness": {"baseColorTexture": {"index": 3}}}
SAMPLERS = [
    {"wrapS": 10497, "wrapT": 33648, "magFilter": 9728, "minFilter": 9987},  # repeat / mirror
    {"wrapS": 33071, "wrapT": 33071},  # clamp / clamp
]
TEXTURES = [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 1}, {"source": 2},
            {"source": 1, "sampler": 1}]

# --- two nodes ----------------------------------------------------------------------------------

# A triangle in the plane x + y = 1 with its plane normal, and a tangent orthogonal to it.
TRI_POSITIONS = np.array([[1, 0, 0], [0, 1, 0], [0, 1, 1]], dtype=np.float32)
TRI_NORMALS = np.array([[1, 1, 0]] * 3, dtype=np.float32) / np.float32(math.sqrt(2.0))
TRI_TANGENTS = np.array([[0, 0, 1, -1]] * 3, dtype=np.float32)
TRI_INDICES = np.array([0, 1, 2], dtype=np.uint8)

STRIP_POSITIONS = np.array([[0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0], [2, 0, 0]], dtype=np.float32)
STRIP_COLORS = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255], [0, 0, 0]],
                        dtype=np.uint8)
# Sparse accessor: the base positions are STRIP_POSITIONS, vertex 4 is replaced by SPARSE_VALUE.
SPARSE_INDEX = 4
SPARSE_VALUE = np.array([[2, 1, 0]], dtype=np.float32)

PARENT = {"name": "parent", "translation": [1.0, 2.0, 3.0],
          "rotation": [0.0, math.sin(math.pi / 4), 0.0, math.cos(math.pi / 4)],  # 90 deg about +y
          "scale": [2.0, 1.0, 0.5]}
CHILD_A_MATRIX = [0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0, 1, 0, 1]  # column-major
CHILD_B = {"name": "child_b", "translation": [0.0, 0.0, 5.0]}
MIRROR = {"name": "mirror", "scale": [-1.0, 1.0, 1.0], "translation": [0.0, -3.0, 0.0]}
PAIR_MATERIAL = {"name": "pair", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1.0],
                                                         "metallicFactor": 0.0}}

# --- alpha and vertex colours -------------------------------------------------------------------

ALPHA_MATERIALS = [
    {"name": "masked", "alphaMode": "MASK", "alphaCutoff": 0.3,
     "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 0.9],
                              "baseColorTexture": {"index": 0}}},
    {"name": "blended", "alphaMode": "BLEND", "doubleSided": True,
     "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
]
COLORS_FLOAT3 = np.array([[0.25, 0.5, 1.0], [1.0, 0.0, 0.125], [0.0, 0.75, 0.5]], dtype=np.float32)
COLORS_U8 = np.array([[255, 0, 128, 255], [0, 255, 64, 128], [1, 2, 3, 0]], dtype=np.uint8)
COLORS_U16 = np.array([[65535, 0, 32768, 65535], [0, 65535, 1, 16384], [300, 600, 900, 0]],
                      dtype=np.uint16)

# --- instancing -------------------------------------------------------------------------------------

BOX_POSITIONS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1]],
                         dtype=np.float32)
BOX_NORMALS = np.array([[0, 0, -1]] * 4 + [[0, -1, 0]] * 2, dtype=np.float32)
BOX_INDICES = np.array([0, 2, 1, 0, 3, 2, 0, 1, 5, 0, 5, 4], dtype=np.uint16)
SHARED_NODES = [{"name": "left", "translation": [-3.0, 0.0, 0.0]},
                {"name": "mirrored", "translation": [3.0, 0.0, 0.0], "scale": [-1.0, 1.0, 1.0]}]
INSTANCING_PARENT = {"name": "crowd", "translation": [0.0, 10.0, 0.0], "scale": [2.0, 2.0, 2.0]}
INSTANCING_NODE = {"name": "instanced", "rotation": [0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)]}
INSTANCE_TRANSLATIONS = np.array([[0, 0, 0], [5, 0, 0], [0, 0, -5]], dtype=np.float32)
# Rotations as normalized shorts (KHR_mesh_quantization style): identity, 90 deg about y, 180 about x.
INSTANCE_ROTATIONS = np.array([[0, 0, 0, 32767], [0, 23170, 0, 23170], [32767, 0, 0, 0]], dtype=np.int16)
INSTANCE_SCALES = np.array([[1, 1, 1], [0.5, 2, 1], [-1, 1, 1]], dtype=np.float32)  # the last mirrors
SINGLE_NODE = {"name": "single", "translation": [0.0, -4.0, 0.0]}

# --- coverage (alpha MASK) and many instances --------------------------------------------------------

CUTOUT = np.zeros((4, 4, 4), dtype=np.uint8)
CUTOUT[..., 3] = 255 * ((np.arange(4)[:, None] + np.arange(4)[None, :]) % 2 == 0)  # opaque where row + col is even
CUTOUT_POSITIONS = np.array([[-1, 1, 0], [1, 1, 0], [1, -1, 0], [-1, -1, 0]], dtype=np.float32)
CUTOUT_MATERIAL = {"name": "cutout", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True,
                   "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0,
                                            "baseColorTexture": {"index": 0}}}

CUBE_FACES = [(np.array(n, np.float32), np.array(u, np.float32), np.array(v, np.float32))
              for n, u, v in (([1, 0, 0], [0, 1, 0], [0, 0, 1]), ([-1, 0, 0], [0, 0, 1], [0, 1, 0]),
                              ([0, 1, 0], [0, 0, 1], [1, 0, 0]), ([0, -1, 0], [1, 0, 0], [0, 0, 1]),
                              ([0, 0, 1], [1, 0, 0], [0, 1, 0]), ([0, 0, -1], [0, 1, 0], [1, 0, 0]))]
COLORED_CENTRES = (-2.2, 0.0, 2.2)  # x of the three quads' centres
COLORED_MATERIALS = [
    {"name": "tinted", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.8, 0.7, 1.0], "metallicFactor": 0.0}},
    {"name": "faded", "alphaMode": "MASK", "alphaCutoff": 0.5,
     "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 0.0}},
    {"name": "plain", "pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.6, 0.9, 1.0], "metallicFactor": 0.0}},
]


def tinted_color(lx, ly):
    """COLOR_0 of the first quad at local coordinates (lx, ly) in [-1, 1]^2: linear in both."""
    return np.stack([0.2 + 0.3 * lx, 0.3 + 0.2 * ly, 0.4 + 0.1 * lx + 0.1 * ly, np.ones_like(lx)], axis=-1)


def faded_color(lx, ly):
    """COLOR_0 of the second quad: white, alpha from 0 at its left edge to 1 at its right."""
    return np.stack([np.ones_like(lx)] * 3 + [(lx + 1.0) / 2.0], axis=-1)


GRID = np.arange(4, dtype=np.float32) * 2.5 - 3.75
GRID_TRANSLATIONS = np.stack(np.meshgrid(GRID, GRID, GRID, indexing="ij"), axis=-1).reshape(-1, 3)
GRID_ANGLES = np.arange(64, dtype=np.float32) * np.float32(0.1)
GRID_ROTATIONS = np.stack([np.zeros(64), np.sin(GRID_ANGLES / 2), np.zeros(64), np.cos(GRID_ANGLES / 2)],
                          axis=1).astype(np.float32)  # about +y
GRID_SCALES = np.repeat((0.5 + 0.5 * (np.arange(64) % 3 == 0)).astype(np.float32)[:, None], 3, axis=1)
GRID_MATERIAL = {"name": "cubes", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.5, 0.2, 1.0],
                                                          "metallicFactor": 0.0, "roughnessFactor": 0.6}}

# --- material layers --------------------------------------------------------------------------------

LAYER_MATERIALS = [
    {"name": "coated", "extensions": {"KHR_materials_clearcoat": {
        "clearcoatFactor": 0.75, "clearcoatTexture": {"index": 0},
        "clearcoatRoughnessFactor": 0.25, "clearcoatRoughnessTexture": {"index": 0},
        "clearcoatNormalTexture": {"index": 0, "scale": 0.5}}}},
    {"name": "velvet", "extensions": {"KHR_materials_sheen": {
        "sheenColorFactor": [0.5, 0.25, 1.0], "sheenColorTexture": {"index": 0},
        "sheenRoughnessFactor": 0.625, "sheenRoughnessTexture": {"index": 0}}}},
    {"name": "tinted", "extensions": {"KHR_materials_specular": {
        "specularFactor": 0.5, "specularTexture": {"index": 0},
        "specularColorFactor": [1.0, 0.5, 0.25], "specularColorTexture": {"index": 1}}}},
    {"name": "absorbing", "extensions": {
        "KHR_materials_transmission": {"transmissionFactor": 1.0},
        "KHR_materials_volume": {"thicknessFactor": 0.2, "attenuationColor": [0.9, 0.5, 0.1],
                                 "attenuationDistance": 0.05}}},
    {"name": "thin", "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.5}}},
    {"name": "volume defaults", "extensions": {"KHR_materials_volume": {}}},
]
LAYER_EXTENSIONS = ["KHR_materials_clearcoat", "KHR_materials_sheen", "KHR_materials_specular",
                    "KHR_materials_transmission", "KHR_materials_volume"]

# --- an imperfect file --------------------------------------------------------------------------------

IGNORED_EXTENSIONS = ["KHR_lights_punctual", "KHR_materials_unlit"]
MISSING_TEXTURE = "missing.png"

# --- OBJ and PLY ----------------------------------------------------------------------------------

MTL = """\
# test materials
newmtl textured
Kd 0.5 0.6 0.7
Ks 0.5 0.5 0.5
Ns 98
map_Kd -o 0.25 0.5 -s 2 2 checker.png

newmtl glass
Kd 1 1 1
Ks 1 1 1
Ns 1000
Ni 1.45
d 0.1
illum 7

newmtl lamp
Kd 0 0 0
Ke 3 2 1

newmtl mirror
Kd 0 0 0
Ks 0.9 0.8 0.7
Pr 0.05
"""

OBJ = """\
# four material groups
mtllib materials.mtl
v -1 1 0
v 1 1 0
v 1 -1 0
v -1 -1 0
v 0 0 1
v 2 0 1
vt 0 1
vt 1 1
vt 1 0
vt 0 0
vn 0 0 1
usemtl textured
f 1/1/1 4/4/1 3/3/1 2/2/1
usemtl glass
f 1 4 5
usemtl lamp
f 4 3 5
usemtl mirror
f 3 2 6
"""

PLY = """\
ply
format ascii 1.0
comment square pyramid: four triangles and a quad base
element vertex 5
property float x
property float y
property float z
property float nx
property float ny
property float nz
property uchar red
property uchar green
property uchar blue
element face 5
property list uchar int vertex_indices
end_header
-1 0 -1 0 -1 0 255 0 0
1 0 -1 0 -1 0 0 255 0
1 0 1 0 -1 0 0 0 255
-1 0 1 0 -1 0 128 128 128
0 1 0 0 1 0 255 255 255
3 0 4 1
3 1 4 2
3 2 4 3
3 3 4 0
4 0 1 2 3
"""


def triangle_primitive(b: BufferBuilder, material: int | None = None, **attributes) -> dict:
    """The unit triangle TRI_POSITIONS with extra attributes (name -> accessor index)."""
    primitive = {"attributes": {"POSITION": b.accessor(TRI_POSITIONS), **attributes},
                 "indices": b.accessor(TRI_INDICES)}
    if material is not None:
        primitive["material"] = material
    return primitive


def alpha_colors_document() -> dict:
    b = BufferBuilder()
    uv = b.accessor(np.array([[0, 0], [1, 0], [0, 1]], dtype=np.float32))
    primitives = [
        triangle_primitive(b, 0, TEXCOORD_0=uv, COLOR_0=b.accessor(COLORS_FLOAT3)),
        triangle_primitive(b, 1, TEXCOORD_0=uv, COLOR_0=b.accessor(COLORS_U8, normalized=True)),
        triangle_primitive(b, 1, COLOR_0=b.accessor(COLORS_U16, normalized=True)),
    ]
    return {
        "asset": {"version": "2.0", "generator": "Lantern tests/data/make_test_models.py"},
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "panel", "mesh": 0}],
        "meshes": [{"name": "panel", "primitives": primitives}],
        "materials": ALPHA_MATERIALS,
        "textures": [{"source": 0}],
        "images": [{"uri": "alpha.png"}],
        "accessors": b.accessors, "bufferViews": b.views, "buffers": data_uri_buffer(b),
    }


def instancing_document() -> dict:
    b = BufferBuilder()
    box = {"attributes": {"POSITION": b.accessor(BOX_POSITIONS), "NORMAL": b.accessor(BOX_NORMALS)},
           "indices": b.accessor(BOX_INDICES)}
    rotations = b.accessor(INSTANCE_ROTATIONS, normalized=True)
    gpu = {"EXT_mesh_gpu_instancing": {"attributes": {
        "TRANSLATION": b.accessor(INSTANCE_TRANSLATIONS), "ROTATION": rotations,
        "SCALE": b.accessor(INSTANCE_SCALES)}}}
    return {
        "asset": {"version": "2.0", "generator": "Lantern tests/data/make_test_models.py"},
        "extensionsUsed": ["EXT_mesh_gpu_instancing"],
        "extensionsRequired": ["EXT_mesh_gpu_instancing"],
        "scene": 0, "scenes": [{"nodes": [0, 1, 2, 4]}],
        "nodes": [dict(SHARED_NODES[0], mesh=0), dict(SHARED_NODES[1], mesh=0),
                  dict(INSTANCING_PARENT, children=[3]),
                  dict(INSTANCING_NODE, mesh=1, extensions=gpu),
                  dict(SINGLE_NODE, mesh=2)],
        "meshes": [{"name": "shared box", "primitives": [box]},
                   {"name": "crowd box", "primitives": [dict(box)]},
                   {"name": "single", "primitives": [triangle_primitive(b)]}],
        "accessors": b.accessors, "bufferViews": b.views, "buffers": data_uri_buffer(b),
    }


def cutout_document() -> dict:
    b = BufferBuilder()
    quad = {"attributes": {"POSITION": b.accessor(CUTOUT_POSITIONS), "NORMAL": b.accessor(QUAD_NORMALS),
                           "TEXCOORD_0": b.accessor(QUAD_UV0)},
            "indices": b.accessor(QUAD_INDICES), "material": 0}
    return {
        "asset": {"version": "2.0", "generator": "Lantern tests/data/make_test_models.py"},
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "cutout", "mesh": 0}],
        "meshes": [{"name": "cutout", "primitives": [quad]}],
        "materials": [CUTOUT_MATERIAL],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 33071, "wrapT": 33071}],
        "images": [{"uri": "cutout.png"}],
        "accessors": b.accessors, "bufferViews": b.views, "buffers": data_uri_buffer(b),
    }


def colored_quads_document() -> dict:
    b = BufferBuilder()
    lx, ly = QUAD_POSITIONS[:, 0].astype(np.float64), QUAD_POSITIONS[:, 1].astype(np.float64)
    normals, indices = b.accessor(QUAD_NORMALS), b.accessor(QUAD_INDICES)
    primitives = []
    for k, (cx, color) in enumerate(zip(COLORED_CENTRES, (tinted_color, faded_color, None))):
        attributes = {"POSITION": b.accessor(QUAD_POSITIONS + np.float32([cx, 0.0, 0.0])), "NORMAL": normals}
        if color is not None:
            attributes["COLOR_0"] = b.accessor(color(lx, ly).astype(np.float32))
        primitives.append({"attributes": attributes, "indices": indices, "material": k})
    return {
        "asset": {"version": "2.0", "generator": "Lantern tests/data/make_test_models.py"},
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "quads", "mesh": 0}],
        "meshes": [{"name": "quads", "primitives": primitives}],
        "materials": COLORED_MATERIALS,
        "accessors": b.accessors, "bufferViews": b.views, "buffers": data_uri_buffer(b),
    }


def cube_arrays() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A unit cube centred on the origin: positions, normals (4 corners per face) and indices,
    counter-clockwise seen from outside."""
    positions, normals, indices = [], [], []
    for n, u, v in CUBE_FACES:
        base = len(positions)
        positions += [0.5 * (n + su * u + sv * v) for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        normals += [n] * 4
        indices += [base, base + 1, base + 2, base, base + 2, base + 3]
    return (np.array(positions, np.float32), np.array(normals, np.float32), np.array(indices, np.uint16))


def simple_instancing_document() -> dict:
    b = BufferBuilder()
    positions, normals, indices = cube_arrays()
    cube = {"attributes": {"POSITION": b.accessor(positions), "NORMAL": b.accessor(normals)},
            "indices": b.accessor(indices), "material": 0}
    gpu = {"EXT_mesh_gpu_instancing": {"attributes": {
        "TRANSLATION": b.accessor(GRID_TRANSLATIONS), "ROTATION": b.accessor(GRID_ROTATIONS),
        "SCALE": b.accessor(GRID_SCALES)}}}
    return {
        "asset": {"version": "2.0", "generator": "Lantern tests/data/make_test_models.py"},
        "extensionsUsed": ["EXT_mesh_gpu_instancing"],
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "cubes", "mesh": 0, "extensions": gpu}],
        "meshes": [{"name": "cube", "primitives": [cube]}],
        "materials": [GRID_MATERIAL],
        "accessors": b.accessors, "bufferViews": b.views, "buffers": data_uri_buffer(b),
    }


def layers_document() -> dict:
    b = BufferBuilder()
    uv = b.accessor(np.array([[0, 0], [1, 0], [0, 1]], dtype=np.float32))
    normals = b.accessor(TRI_NORMALS)
    primitives = [triangle_primitive(b, m, NORMAL=normals, TEXCOORD_0=uv)
                  for m in range(len(LAYER_MATERIALS))]
    return {
        "asset": {"version": "2.0", "generator": "Lantern tests/data/make_test_models.py"},
        "extensionsUsed": LAYER_EXTENSIONS,
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "swatches", "mesh": 0}],
        "meshes": [{"name": "swatches", "primitives": primitives}],
        "materials": LAYER_MATERIALS,
        "textures": [{"source": 0}, {"source": 1}],
        "images": [{"uri": "layer.png"}, {"uri": "rgb16.png"}],
        "accessors": b.accessors, "bufferViews": b.views, "buffers": data_uri_buffer(b),
    }


def imperfect_document() -> dict:
    b = BufferBuilder()
    uv = b.accessor(np.array([[0, 0], [1, 0], [0, 1]], dtype=np.float32))
    return {
        "asset": {"version": "2.0", "generator": "Lantern tests/data/make_test_models.py"},
        "extensionsUsed": IGNORED_EXTENSIONS + ["KHR_texture_transform"],
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "lamp", "mesh": 0,
                   "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point"}]}},
        "meshes": [{"name": "lamp", "primitives": [triangle_primitive(b, 0, TEXCOORD_0=uv)]}],
        "materials": [{"name": "painted", "pbrMetallicRoughness": {
            "baseColorFactor": [0.5, 0.25, 0.125, 1.0], "baseColorTexture": {"index": 0},
            "metallicRoughnessTexture": {"index": 0}},
            "extensions": {"KHR_materials_unlit": {}}}],
        "textures": [{"source": 0}],
        "images": [{"uri": MISSING_TEXTURE}],
        "accessors": b.accessors, "bufferViews": b.views, "buffers": data_uri_buffer(b),
    }


def quad_document(embed_images: bool) -> tuple[dict, bytes]:
    b = BufferBuilder()
    attributes = {
        "POSITION": b.accessor(QUAD_POSITIONS),
        "NORMAL": b.accessor(QUAD_NORMALS),
        "TEXCOORD_0": b.accessor(QUAD_UV0),
        "TEXCOORD_1": b.accessor(QUAD_UV1),
    }
    indices = b.accessor(QUAD_INDICES)
    names = ["checker.png", "mr.png", "normal.png"]
    if embed_images:
        images = [{"bufferView": b.view(png_bytes(p)), "mimeType": "image/png", "name": n}
                  for p, n in zip((CHECKER, MR, NORMAL), names)]
    else:
        images = [{"uri": n} for n in names]
    doc = {
        "asset": {"version": "2.0", "generator": "Lantern tests/data/make_test_models.py"},
        "extensionsUsed": ["KHR_texture_transform", "KHR_materials_emissive_strength",
                           "KHR_materials_transmission", "KHR_materials_ior"],
        "extensionsRequired": ["KHR_texture_transform"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "quad", "mesh": 0, "translation": QUAD_TRANSLATION}],
        "meshes": [{"name": "quad", "primitives": [
            {"attributes": attributes, "indices": indices, "material": 0}]}],
        "materials": [QUAD_MATERIAL, SECOND_MATERIAL],
        "textures": TEXTURES,
        "samplers": SAMPLERS,
        "images": images,
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": len(b.data)}],
    }
    return doc, bytes(b.data)


def two_nodes_document() -> dict:
    b = BufferBuilder()
    tri = {"attributes": {"POSITION": b.accessor(TRI_POSITIONS), "NORMAL": b.accessor(TRI_NORMALS),
                          "TANGENT": b.accessor(TRI_TANGENTS)},
           "indices": b.accessor(TRI_INDICES), "material": 0}
    strip = {"attributes": {"POSITION": b.accessor(STRIP_POSITIONS),
                            "COLOR_0": b.accessor(STRIP_COLORS, normalized=True)},
             "mode": 5, "material": 0}
    sparse = {"count": 1,
              "indices": {"bufferView": b.view(np.array([SPARSE_INDEX], np.uint8).tobytes()),
                          "componentType": 5121},
              "values": {"bufferView": b.view(SPARSE_VALUE.tobytes())}}
    base = b.accessors[strip["attributes"]["POSITION"]]
    sparse_positions = dict(base, sparse=sparse)
    sparse_positions["max"] = [2.0, 1.0, 0.0]
    b.accessors.append(sparse_positions)
    no_material = {"attributes": {"POSITION": len(b.accessors) - 1},
                   "indices": b.accessor(np.array([0, 2, 1, 2, 4, 3], np.uint16))}
    return {
        "asset": {"version": "2.0", "generator": "Lantern tests/data/make_test_models.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 3]}],
        "nodes": [
            dict(PARENT, children=[1, 2]),
            {"name": "child_a", "mesh": 0, "matrix": CHILD_A_MATRIX},
            dict(CHILD_B, mesh=0),
            dict(MIRROR, mesh=1),
        ],
        "meshes": [{"name": "tri", "primitives": [tri]},
                   {"name": "pair", "primitives": [strip, no_material]}],
        "materials": [PAIR_MATERIAL],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": data_uri_buffer(b),
    }


def main(out: Path = HERE) -> None:
    for name, pixels in (("checker.png", CHECKER), ("mr.png", MR), ("normal.png", NORMAL),
                         ("alpha.png", ALPHA), ("layer.png", LAYER), ("cutout.png", CUTOUT)):
        (out / name).write_bytes(png_bytes(pixels))
    (out / "rgb16.png").write_bytes(png16_bytes(RGB16))

    doc, binary = quad_document(embed_images=False)
    doc["buffers"][0]["uri"] = "textured_quad.bin"
    (out / "textured_quad.bin").write_bytes(binary)
    (out / "textured_quad.gltf").write_text(json.dumps(doc, indent=1) + "\n")

    doc, binary = quad_document(embed_images=True)
    (out / "textured_quad.glb").write_bytes(glb_bytes(doc, binary))

    (out / "two_nodes.gltf").write_text(json.dumps(two_nodes_document(), indent=1) + "\n")
    (out / "materials.mtl").write_text(MTL)
    (out / "materials.obj").write_text(OBJ)
    (out / "pyramid.ply").write_text(PLY)
    for name, document in (("alpha_colors.gltf", alpha_colors_document()),
                           ("instancing.gltf", instancing_document()),
                           ("layers.gltf", layers_document()),
                           ("imperfect.gltf", imperfect_document()),
                           ("cutout.gltf", cutout_document()),
                           ("colored_quads.gltf", colored_quads_document()),
                           ("simple_instancing.gltf", simple_instancing_document())):
        (out / name).write_text(json.dumps(document, indent=1) + "\n")


if __name__ == "__main__":
    main()

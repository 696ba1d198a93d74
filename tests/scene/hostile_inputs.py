"""Small input files that ask for far more than they hold, or reach outside their folder.

Each writer takes a folder, writes the case there and returns the path a user would open. The
input-limit tests and the fuzz test open them; each must end in a clean load or a one-line
SceneError, never in a traceback, a hang or an allocation the size of what the file declares.
"""
from __future__ import annotations

import base64
import json
import os
import struct
from pathlib import Path

import numpy as np

SCENE_HEADER = """[scene]
geometry = "{geometry}"

[camera]
position = [0.0, 1.0, 6.0]
look_at = [0.0, 0.0, 0.0]

[render]
width = {width}
height = {height}
spp = 4

[environment]
type = "constant"
color = [0.5, 0.5, 0.5]

[materials.white]
type = "diffuse"
base_color = [0.8, 0.8, 0.8]
{extra}
"""


def scene_text(objects: str, geometry: str = "sdf", width: int = 32, height: int = 18,
               extra: str = "") -> str:
    return SCENE_HEADER.format(geometry=geometry, width=width, height=height, extra=extra) + objects


def _data_uri(data: bytes) -> str:
    return "data:application/octet-stream;base64," + base64.b64encode(data).decode("ascii")


def triangle_gltf(extra_doc: dict | None = None, image_uri: str | None = None,
                  buffer_uri: str | None = None) -> dict:
    """A one-triangle glTF (positions and UVs in a data-URI buffer), optionally textured by
    `image_uri`, or reading its buffer from `buffer_uri`."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    uvs = np.array([[0, 0], [1, 0], [0, 1]], np.float32)
    blob = positions.tobytes() + uvs.tobytes()
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(blob), "uri": buffer_uri or _data_uri(blob)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {}}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }
    if image_uri is not None:
        doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
        doc["textures"] = [{"source": 0}]
        doc["images"] = [{"uri": image_uri}]
    doc.update(extra_doc or {})
    return doc


def write_json(path: Path, doc: dict) -> Path:
    path.write_text(json.dumps(doc, separators=(",", ":")))
    return path


def huge_accessor_gltf(folder: Path, count: int = 400_000_000) -> Path:
    """An accessor without a bufferView (all zeros) that declares `count` VEC3 floats: a few
    hundred bytes asking for gigabytes."""
    doc = {"asset": {"version": "2.0"},
           "accessors": [{"componentType": 5126, "count": count, "type": "VEC3"}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "nodes": [{"mesh": 0}]}
    return write_json(folder / "huge_accessor.gltf", doc)


def huge_png(path: Path, size: int = 12000) -> Path:
    """A black grey-scale PNG of size x size pixels: about a kilobyte per megapixel on disk."""
    from PIL import Image

    Image.new("L", (size, size), 0).save(path, optimize=True)
    return path


def huge_texture_gltf(folder: Path, size: int = 12000) -> Path:
    huge_png(folder / "huge.png", size)
    return write_json(folder / "huge_texture.gltf", triangle_gltf(image_uri="huge.png"))


def huge_hdr(path: Path, width: int = 100000, height: int = 100000) -> Path:
    """A Radiance header that declares width x height pixels, followed by a few bytes."""
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"
                     + f"-Y {height} +X {width}\n".encode() + bytes(64))
    return path


def huge_hdr_scene(folder: Path) -> Path:
    huge_hdr(folder / "huge.hdr")
    text = scene_text('[[objects]]\ntype = "sphere"\nmaterial = "white"\n').replace(
        'type = "constant"\ncolor = [0.5, 0.5, 0.5]', 'type = "map"\nfile = "huge.hdr"')
    path = folder / "huge_hdr.toml"
    path.write_text(text)
    return path


def huge_film_scene(folder: Path, width: int = 100000, height: int = 100000) -> Path:
    path = folder / "huge_film.toml"
    path.write_text(scene_text('[[objects]]\ntype = "sphere"\nmaterial = "white"\n',
                               width=width, height=height))
    return path


def sphere_union_scene(folder: Path, count: int) -> Path:
    """One top-level union of `count` unit-radius spheres on a grid (radius 0.1)."""
    side = int(np.ceil(np.sqrt(count)))
    lines = ['[[objects]]', 'type = "union"', 'material = "white"']
    for i in range(count):
        x, z = (i % side - side / 2) * 0.3, (i // side - side / 2) * 0.3
        lines += ['[[objects.children]]', 'type = "sphere"', 'radius = 0.1',
                  f'translate = [{x:.3f}, 0.0, {z:.3f}]']
    path = folder / f"union_{count}.toml"
    path.write_text(scene_text("\n".join(lines) + "\n"))
    return path


def deep_union_scene(folder: Path, depth: int) -> Path:
    """Unions nested `depth` deep, each holding a sphere and the next union."""
    lines = ['[[objects]]', 'type = "union"', 'material = "white"']
    prefix = "objects"
    for level in range(depth):
        prefix += ".children"
        lines += [f"[[{prefix}]]", 'type = "sphere"', f"radius = {0.1 + 0.001 * level:.3f}"]
        if level < depth - 1:
            lines += [f"[[{prefix}]]", 'type = "union"']
        else:
            lines += [f"[[{prefix}]]", 'type = "box"']
    path = folder / f"deep_union_{depth}.toml"
    path.write_text(scene_text("\n".join(lines) + "\n"))
    return path


def truncated_stl(folder: Path) -> Path:
    """A binary STL declaring 12 triangles whose data stops inside the third."""
    triangles = 12
    body = b"".join(struct.pack("<12fH", *([0.0] * 3), *np.random.default_rng(0).random(9), 0)
                    for _ in range(triangles))
    data = bytes(80) + struct.pack("<I", triangles) + body
    path = folder / "truncated.stl"
    path.write_bytes(data[:84 + 2 * 50 + 17])
    return path


def huge_emission_scene(folder: Path) -> Path:
    extra = '\n[materials.sun]\ntype = "diffuse"\nemission = [1.0, 1.0, 1.0]\nemission_strength = 1e39\n'
    path = folder / "huge_emission.toml"
    path.write_text(scene_text('[[objects]]\ntype = "sphere"\nmaterial = "sun"\n', extra=extra))
    return path


def symlink_loop_model(folder: Path) -> Path:
    """loop_a.glb -> loop_b.glb -> loop_a.glb."""
    a, b = folder / "loop_a.glb", folder / "loop_b.glb"
    os.symlink(b.name, a)
    os.symlink(a.name, b)
    return a


def symlink_loop_scene(folder: Path) -> Path:
    """A scene whose model file is a symlink loop."""
    model = symlink_loop_model(folder)
    path = folder / "loop_scene.toml"
    path.write_text(scene_text(f'[[objects]]\ntype = "mesh"\nfile = "{model.name}"\n',
                               geometry="mesh"))
    return path


def escaping_uri_gltf(folder: Path) -> Path:
    """A model in folder/model/ whose texture is folder/outside.png, named '../outside.png'."""
    from PIL import Image

    Image.new("RGB", (2, 2), (255, 0, 0)).save(folder / "outside.png")
    (folder / "model").mkdir(exist_ok=True)
    return write_json(folder / "model" / "escaping.gltf", triangle_gltf(image_uri="../outside.png"))


def png_declaring(path: Path, width: int, height: int) -> Path:
    """A 2x2 PNG whose header (IHDR) claims width x height: only a reader that decodes before it
    checks the size would find out."""
    import io

    from PIL import Image

    buffer = io.BytesIO()
    Image.new("L", (2, 2), 0).save(buffer, format="PNG")
    data = bytearray(buffer.getvalue())
    struct.pack_into(">II", data, 16, width, height)
    path.write_bytes(bytes(data))
    return path


def exr_declaring(path: Path, width: int, height: int) -> Path:
    """A 4x8 EXR whose header's data window claims width x height."""
    from renderer.output.image_io import write_exr

    write_exr(path, np.ones((4, 8, 3), np.float32))
    data = bytearray(path.read_bytes())
    for key in (b"dataWindow\0box2i\0", b"displayWindow\0box2i\0"):
        at = data.index(key) + len(key) + 4  # attribute name, type, size
        struct.pack_into("<4i", data, at, 0, 0, width - 1, height - 1)
    path.write_bytes(bytes(data))
    return path

"""What `python app.py info` says about a mesh scene's model files and its device memory.

Per model file: its materials (workflow, layers, glTF extensions, ignored ones marked), its
textures (size, storage, decoding, users), the extensions it uses and those ignored, unique and
instanced triangles and the instances. For the scene: device bytes of the texture pages, of the
triangle arrays as uploaded, and an upper bound for the BVH.
"""
from __future__ import annotations

from dataclasses import fields

from renderer.scene.errors import SceneError
from renderer.scene.model_formats.gltf import SUPPORTED_GLTF_EXTENSIONS
from renderer.scene.mesh_model import MeshAsset, PbrMaterial

# BVH layout on the device (renderer/geometry/mesh_geometry.py): per node lo, hi (3 x f32 each)
# and a link (3 x i32); per primitive one i32 slot. A tree over N primitives has at most 2N - 1
# nodes (every leaf holds at least one primitive).
BVH_NODE_BYTES = 36
BVH_SLOT_BYTES = 4


def megabytes(n: int) -> str:
    return f"{n / 1e6:.1f} MB"


def workflow(asset: MeshAsset, material: PbrMaterial) -> str:
    suffix = asset.path.suffix.lower() if asset.path else ""
    if suffix in (".obj",):
        return "MTL, mapped to metallic-roughness"
    if suffix in (".ply", ".stl"):
        return "default grey (the format has no materials)"
    if "KHR_materials_pbrSpecularGlossiness" in material.extensions:
        return "specular-glossiness (ignored: read as metallic-roughness)"
    if "KHR_materials_unlit" in material.extensions:
        return "unlit (ignored: shaded as metallic-roughness)"
    return "metallic-roughness"


def layers(m: PbrMaterial) -> list[str]:
    """The parts of the material model a material switches on, beyond a plain opaque base."""
    out = []
    if m.transmission_factor > 0.0:
        out.append("transmission (thin-walled)" if m.thin_walled else "transmission + volume")
    if m.clearcoat_factor > 0.0:
        out.append("clearcoat")
    if max(m.sheen_color_factor) > 0.0:
        out.append("sheen")
    if m.specular_factor != 1.0 or m.specular_color_factor != (1.0, 1.0, 1.0) or m.specular_texture \
            or m.specular_color_texture:
        out.append("specular")
    if m.is_emissive:
        out.append("emissive")
    if m.alpha_mode != "OPAQUE":
        out.append(f"alpha {m.alpha_mode}")
    return out


def model_lines(asset: MeshAsset, name: str) -> list[str]:
    lines = [f"model:       {name}"]
    unique, drawn = asset.triangle_count, asset.drawn_triangle_count
    lines.append(f"  triangles  {unique} unique, {drawn} drawn"
                 + (f" ({asset.instanced_triangle_count} by instances)" if asset.instanced else ""))
    if asset.instanced:
        parts = [f"'{i.mesh.name}' x{i.instance_count}" for i in asset.instanced]
        lines.append(f"  instances  {sum(i.instance_count for i in asset.instanced)} of "
                     f"{len(asset.instanced)} meshes: {', '.join(parts)}")
    else:
        lines.append("  instances  none (every mesh is placed once)")
    if asset.extensions_used:
        ignored = set(asset.extensions_ignored)
        shown = [e + (" (ignored)" if e in ignored else "") for e in asset.extensions_used]
        lines.append(f"  extensions {', '.join(shown)}")
    lines.append(f"  materials  {len(asset.materials)}")
    for m in asset.materials:
        extensions = [e + ("" if e in SUPPORTED_GLTF_EXTENSIONS else " (ignored)") for e in m.extensions]
        details = "; ".join(part for part in (", ".join(layers(m)), ", ".join(extensions)) if part)
        lines.append(f"    {m.name!r:<24} {workflow(asset, m)}" + (f"; {details}" if details else ""))
    users: dict[int, list[str]] = {}
    for m in asset.materials:
        for slot, ref in m.texture_slots.items():
            users.setdefault(ref.texture, []).append(f"{m.name} {slot}")
    stored = len({id(image.pixels) for image in asset.images})
    lines.append(f"  textures   {len(asset.images)} entries, {stored} stored")
    for i, image in enumerate(asset.images):
        h, w = image.shape
        decoding = "sRGB colour" if image.srgb else "linear data"
        lines.append(f"    [{i}] {w}x{h} {image.storage:<5} {decoding:<11} {image.label}; used by "
                     + ", ".join(users.get(i, ["-"])))
    return lines


def device_lines(mesh_scene) -> list[str]:
    """Device memory of a `MeshScene` (renderer/mesh_world.py): texture pages, triangle arrays, BVH bound."""
    data = mesh_scene.data
    textures = mesh_scene.atlas.nbytes if mesh_scene.atlas is not None else 0
    mipmapped = mesh_scene.atlas is not None and len(mesh_scene.atlas.level_rects) > 0
    triangles = sum(getattr(data, f.name).nbytes for f in fields(data)
                    if f.name.startswith("tri_") and getattr(data, f.name) is not None)
    n = data.primitive_count
    bvh = (2 * n - 1) * BVH_NODE_BYTES + n * BVH_SLOT_BYTES if n else 0
    return [
        "device memory:",
        f"  textures   {megabytes(textures)}"
        + (" (with their mip levels: render.texture_filter)" if mipmapped else ""),
        f"  triangles  {megabytes(triangles)} ({len(data.tri_vertices)} triangles as uploaded)",
        f"  BVH        at most {megabytes(bvh)} (2N - 1 nodes of {BVH_NODE_BYTES} bytes and "
        f"{BVH_SLOT_BYTES} bytes per primitive, N = {n})",
    ]


def scene_report(scene, mesh_scene) -> list[str]:
    """Every model file of a mesh scene, then the scene's device memory."""
    lines, seen = [], set()
    for obj in scene.mesh_objects:
        if obj.kind == "mesh" and obj.file is not None and obj.file not in seen:  # a file's parts: one report
            seen.add(obj.file)
            try:
                asset = scene.model_files.load(obj.file)
            except SceneError:
                if not obj.skip_unreadable:
                    raise
                lines.append(f"model:       {obj.file.name}  (left out: it does not read)")
                continue
            lines += model_lines(asset, obj.file.name)
    return lines + device_lines(mesh_scene)

"""OBJ files and their MTL material libraries.

Geometry through trimesh (`trimesh.exchange.obj.load_obj`, one mesh per material); the MTL
files are parsed here, so that missing libraries and textures are reported. Mapping:
  Kd -> base colour (default 0.8 grey); d (or 1 - Tr) -> base colour alpha.
  Roughness: Pr if given; else 1.0 when Ks is absent or black (no highlight: matte); else
    from the Phong exponent, alpha = sqrt(2 / (Ns + 2)) (the Beckmann/Phong correspondence of
    Walter et al. 2007), roughness = sqrt(alpha); without Ns, 0.5.
  Metallic: Pm if given; else 1 for a "mirror" (black Kd, non-black Ks; base colour = Ks),
    else 0.
  Ke -> emission (times map_Ke). Ni -> ior when > 1 (Ni = 1 is what most exporters write for
    "unset"; 1.5 is used then). Glass: illum 4, 6, 7 or 9 with d < 1 -> transmission = 1 - d
    (and alpha 1); otherwise d < 1 is alpha blending.
  Textures: map_Kd (base colour, sRGB), map_Ke (emissive, sRGB), norm (normal map), and
    map_Bump / bump only when the image is a tangent-space normal map (blue on average, as
    Blender writes them); height-map bumps are ignored with a warning. Options -o and -s
    become a UV transform, -clamp on becomes clamp wrapping; other options are skipped.
    map_Ka, map_Ks, map_Ns, map_d, map_Pr, map_Pm are ignored.
"""
from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Optional

import numpy as np

from renderer.scene.mesh_model import PbrMaterial, TextureRef
from renderer.scene.model_formats.builder import (
    TRIMESH_PARSE_BYTES_PER_BYTE,
    AssetBuilder,
    MissingTexture,
    default_grey,
    file_reader,
    linear_vertex_colors,
)
from renderer.scene.model_formats.image_decoding import unit_values


_MAP_OPTION_ARITY = {"-o": 3, "-s": 3, "-t": 3, "-mm": 2, "-bm": 1, "-boost": 1, "-texres": 1,
                     "-blendu": 1, "-blendv": 1, "-clamp": 1, "-cc": 1, "-imfchan": 1, "-type": 1}


def _is_number(token: str) -> bool:
    try:
        float(token)
        return True
    except ValueError:
        return False


def _parse_map_statement(args: list[str]) -> tuple[str, dict]:
    """Split `map_Kd -o 0.5 0 -s 2 2 dir/file name.png` into ('dir/file name.png', options)."""
    options: dict[str, list[str]] = {}
    i = 0
    while i < len(args) and args[i].startswith("-") and args[i].lower() in _MAP_OPTION_ARITY:
        key = args[i].lower()
        arity = _MAP_OPTION_ARITY[key]
        values = []
        i += 1
        while len(values) < arity and i < len(args) - 1:
            if key in ("-o", "-s", "-t", "-mm", "-bm", "-boost") and not _is_number(args[i]):
                break
            values.append(args[i])
            i += 1
        options[key] = values
    return " ".join(args[i:]).replace("\\", "/"), options


def _read_text(file: Path) -> str:
    return file.read_bytes().decode("utf-8", errors="replace")


def _parse_mtl(text: str) -> dict[str, dict[str, list[str]]]:
    materials: dict[str, dict[str, list[str]]] = {}
    current = None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        key, _, rest = line.replace("\t", " ").partition(" ")
        key = key.lower()
        if not (key.startswith("map") or key in ("bump", "norm", "disp", "decal", "refl")):
            rest = rest.split("#", 1)[0]  # trailing comment (file names may contain '#')
        if key == "newmtl":
            current = {}
            materials[rest.strip()] = current
        elif current is not None:
            current[key] = rest.split()
    return materials


class _MaterialNamesResolver:
    """Hands trimesh an MTL that only declares names: materials are parsed by this module."""

    def __init__(self, names: list[str]):
        self.data = "".join(f"newmtl {n}\n" for n in names).encode("utf-8")

    def get(self, key):
        return self.data

    def __getitem__(self, key):
        return self.data


def _floats(values: Optional[list[str]], n: int) -> Optional[tuple[float, ...]]:
    if not values:
        return None
    try:
        out = [float(v) for v in values[:n]]
    except ValueError:
        return None
    while len(out) < n:  # "Kd 0.5" means grey
        out.append(out[-1])
    return tuple(out)


def _obj_material(b: AssetBuilder, name: str, entries: dict, directory: Path) -> PbrMaterial:
    kd = _floats(entries.get("kd"), 3) or (0.8, 0.8, 0.8)
    ks = _floats(entries.get("ks"), 3)
    ke = _floats(entries.get("ke"), 3)
    ns = _floats(entries.get("ns"), 1)
    ni = _floats(entries.get("ni"), 1)
    pr = _floats(entries.get("pr"), 1)
    pm = _floats(entries.get("pm"), 1)
    illum = _floats(entries.get("illum"), 1)
    d = _floats(entries.get("d"), 1)
    if d is None and entries.get("tr"):
        tr = _floats(entries.get("tr"), 1)
        d = (1.0 - tr[0],) if tr else None
    dissolve = 1.0 if d is None else min(max(d[0], 0.0), 1.0)

    if pr is not None:
        roughness = pr[0]
    elif ks is None or max(ks) <= 0.0:
        roughness = 1.0
    elif ns is not None:
        roughness = math.sqrt(math.sqrt(2.0 / (max(ns[0], 0.0) + 2.0)))
    else:
        roughness = 0.5
    base = kd
    if pm is not None:
        metallic = pm[0]
    elif max(kd) <= 0.0 and ks is not None and max(ks) > 0.0:
        metallic, base = 1.0, ks
    else:
        metallic = 0.0
    transmission, alpha = 0.0, dissolve
    if illum is not None and int(illum[0]) in (4, 6, 7, 9) and dissolve < 1.0:
        transmission, alpha = 1.0 - dissolve, 1.0
    ior = ni[0] if ni is not None and ni[0] > 1.0 else 1.5

    def texture(key: str, srgb: bool) -> Optional[TextureRef]:
        args = entries.get(key)
        if not args:
            return None
        file_name, options = _parse_map_statement(args)
        if not file_name:
            return None
        what = f"material '{name}' {key}"
        target = b.reference(file_name, what, directory)
        offset = _floats(options.get("-o"), 2) or (0.0, 0.0)
        scale = _floats(options.get("-s"), 2) or (1.0, 1.0)
        # MTL -o/-s act on v-up coordinates; in the stored v-down frame v' = s v + (1 - s - o).
        matrix = ((scale[0], 0.0, offset[0]), (0.0, scale[1], 1.0 - scale[1] - offset[1]),
                  (0.0, 0.0, 1.0))
        wrap = "clamp" if options.get("-clamp", ["off"])[0].lower() == "on" else "repeat"
        index = b.image(("file", str(target)), srgb, f"'{file_name}'",
                        file_reader(b, file_name, what, directory), what)
        if index is None:
            return None  # missing: the material keeps its factors (warned at the end)
        return TextureRef(texture=index, uv_set=0, wrap_s=wrap, wrap_t=wrap,
                          transform=tuple(tuple(float(v) for v in row) for row in matrix))

    normal = texture("norm", False)
    normal_scale = 1.0
    if normal is None:
        for key in ("map_bump", "bump"):
            if entries.get(key):
                file_name, options = _parse_map_statement(entries[key])
                what = f"material '{name}' {key}"
                image_key = ("file", str(b.reference(file_name, what, directory)))
                try:
                    raw = b.decoded_image(image_key, f"'{file_name}'",
                                          file_reader(b, file_name, what, directory))
                except MissingTexture:
                    b.note_missing(image_key, file_name, f"material '{name}' {key}")
                    break
                mean = unit_values(raw[:, :, :3]).reshape(-1, 3).mean(axis=0)
                if mean[2] > 0.6 and abs(mean[0] - 0.5) < 0.2 and abs(mean[1] - 0.5) < 0.2:
                    normal = texture(key, False)
                    bm = _floats(options.get("-bm"), 1)
                    normal_scale = 1.0 if bm is None else bm[0]
                else:
                    b.warn(f"material '{name}': height-map bump '{file_name}' ignored (only "
                           "normal maps are supported)")
                break
    emissive_texture = texture("map_ke", True)
    emission = ke if ke is not None else ((1.0, 1.0, 1.0) if emissive_texture else (0.0, 0.0, 0.0))
    return PbrMaterial(
        name=name,
        base_color_factor=(*(float(c) for c in base), float(alpha)),
        metallic_factor=float(min(max(metallic, 0.0), 1.0)),
        roughness_factor=float(min(max(roughness, 0.0), 1.0)),
        emissive_factor=tuple(float(c) for c in emission),
        transmission_factor=float(transmission),
        ior=float(ior),
        normal_scale=float(normal_scale),
        alpha_mode="BLEND" if alpha < 1.0 else "OPAQUE",
        base_color_texture=texture("map_kd", True),
        normal_texture=normal,
        emissive_texture=emissive_texture,
    )


def _fan_triangulate(faces) -> np.ndarray:
    """(F, k) polygons (trimesh leaves all-quad groups as quads) as (T, 3) triangle fans."""
    if isinstance(faces, np.ndarray) and faces.ndim == 2 and faces.dtype != object:
        k = faces.shape[1]
        if k == 3:
            return faces
        if k < 3:
            raise ValueError(f"faces with {k} vertices")
        return np.concatenate([faces[:, [0, i, i + 1]] for i in range(1, k - 1)], axis=0)
    triangles = [[f[0], f[i], f[i + 1]] for f in faces for i in range(1, len(f) - 1)]
    return np.asarray(triangles, dtype=np.int64).reshape(-1, 3)


def read_obj(b: AssetBuilder) -> None:
    from trimesh.exchange.obj import load_obj

    text = _read_text(b.file)
    b.check_peak("parsing the OBJ file", b.file.stat().st_size * TRIMESH_PARSE_BYTES_PER_BYTE)
    libraries = []
    for match in re.finditer(r"^[ \t]*mtllib[ \t]+(.+?)[ \t]*$", text, flags=re.MULTILINE):
        value = match.group(1).replace("\\", "/")
        whole = b.file.parent / value
        libraries.extend([value] if whole.is_file() else value.split())
    mtl: dict[str, dict] = {}
    for library in libraries:
        target = b.reference(library, "material library")
        if not target.is_file():
            raise b.error(f"material library '{library}' not found")
        b.charge_file(target, "material library")
        for name, entries in _parse_mtl(_read_text(target)).items():
            mtl.setdefault(name, (entries, target.parent))
    index = {}
    for name, (entries, directory) in mtl.items():
        b.materials.append(_obj_material(b, name, entries, directory))
        index[name] = len(b.materials) - 1

    with open(b.file, "rb") as f:
        try:
            kwargs = load_obj(f, resolver=_MaterialNamesResolver(list(mtl)), group_material=True)
        except IndexError as e:  # trimesh indexes its vertex arrays with the face indices
            raise b.error("a face refers to a vertex that does not exist "
                          "(vertex index out of range)") from e
    geometry = kwargs.get("geometry", {})
    default = None
    for key in sorted(geometry, key=str):
        g = geometry[key]
        faces = g.get("faces")
        if faces is None or len(faces) == 0:
            continue
        faces = _fan_triangulate(faces)
        visual = g.get("visual")
        material_name = getattr(getattr(visual, "material", None), "name", None)
        if material_name in index:
            material = index[material_name]
        else:
            if default is None:
                default = default_grey(b)
            material = default
        uv = getattr(visual, "uv", None)
        if uv is not None:
            uv = np.asarray(uv, dtype=np.float64)[:, :2].copy()
            if len(uv) != len(g["vertices"]):
                uv = None
            else:
                uv[:, 1] = 1.0 - uv[:, 1]  # OBJ is v-up
        colors = linear_vertex_colors(g.get("vertex_colors"), len(g["vertices"]))
        where = f"material '{material_name}'" if material_name in index else "faces without a material"
        b.add_mesh(where, g["vertices"], faces, material=material,
                   normals=g.get("vertex_normals"), uv0=uv, colors=colors, name=str(key))


def obj_dependencies(obj_file: Path) -> list[Path]:
    """The files an OBJ model reads besides itself: its material libraries and the texture images
    they name (those that exist; the loader reports missing ones). For checkpoints' fingerprints
    and for shipping a scene to other machines."""
    text = _read_text(obj_file)
    found: list[Path] = []
    for match in re.finditer(r"^[ \t]*mtllib[ \t]+(.+?)[ \t]*$", text, flags=re.MULTILINE):
        value = match.group(1).replace("\\", "/")
        names = [value] if (obj_file.parent / value).is_file() else value.split()
        for library in (obj_file.parent / name for name in names):
            if not library.is_file():
                continue
            found.append(library)
            for entries in _parse_mtl(_read_text(library)).values():
                for key, args in entries.items():
                    if key.startswith("map_") or key in ("bump", "norm", "disp", "decal", "refl"):
                        image = library.parent / _parse_map_statement(args)[0]
                        if image.is_file():
                            found.append(image)
    return found

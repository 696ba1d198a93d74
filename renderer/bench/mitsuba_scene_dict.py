"""A Lantern mesh scene (TOML, or a model file opened as a scene) as Mitsuba 3's scene dictionary,
for `compare` and the benchmarks: the same camera, film (box filter), depth, geometry, materials,
emitters and environment, in Mitsuba's own plugins.

The geometry is taken from the scene's assembly (renderer/scene/mesh_assembly.py), so every
primitive is placed exactly as Lantern places it: triangles as one Mitsuba mesh per material
(with their vertex normals), analytic spheres, quads as rectangles and discs as disks, each with
the to_world that puts Mitsuba's shape on Lantern's. Materials map kind for kind (diffuse;
conductor from eta/k or a named metal; dielectric; principled; null with its medium); where the
two renderers' models differ (a conductor given by its colour, a glTF texture) the nearest Mitsuba
plugin is used and `notes` says so. What Mitsuba cannot express (SDF scenes, the procedural sky,
dispersion, analytic fog) is a ValueError naming it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from renderer.scene.description import MaterialSpec, Scene

NOTE_LIMIT = 8  # notes listed one by one; the rest counted


def scene_dict(scene: Scene, mesh_dir: Path, size: tuple[int, int] | None = None, max_depth: int | None = None,
               spp: int = 16) -> tuple[dict, list[str]]:
    """(Mitsuba's scene dictionary, notes on what is approximated). Triangles are written as PLY
    files into `mesh_dir`, which must outlive the loaded Mitsuba scene. Needs the `mitsuba` package."""
    from renderer.bench.mitsuba_side import _import_mitsuba
    from renderer.scene.mesh_assembly import ModelMaterial, assemble

    mi, _, _ = _import_mitsuba()
    if scene.geometry != "mesh":
        raise ValueError(f"{scene.name}: SDF scenes have no Mitsuba counterpart (Mitsuba traces meshes and shapes)")
    if scene.fog.model == "analytic":
        raise ValueError(f"{scene.name}: analytic fog is Lantern's own approximation; Mitsuba has none")
    if any(m.is_dispersive for m in scene.materials):
        raise ValueError(f"{scene.name}: dispersive glass needs Mitsuba's spectral variants; compared in RGB")
    notes: list[str] = []
    width, height = size or scene.render.image_size
    crop = scene.render.crop if (width, height) == scene.render.image_size else None
    film = {"type": "hdrfilm", "width": int(width), "height": int(height), "rfilter": _rfilter(scene.render)}
    if crop is not None:  # the whole image's film, rendered in the crop window (as Lantern's)
        film.update(width=scene.render.width, height=scene.render.height, crop_offset_x=crop[0],
                    crop_offset_y=crop[1], crop_width=crop[2], crop_height=crop[3])
        width, height = scene.render.width, scene.render.height  # the projection's aspect
    T = mi.ScalarTransform4f
    cam = scene.camera
    result = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(scene.render.max_depth if max_depth is None else max_depth)},
        "sensor": {"type": "perspective", "fov": float(cam.fov), "fov_axis": "y",
                   "to_world": T().look_at(origin=list(cam.position), target=list(cam.look_at), up=list(cam.up)),
                   "film": film,
                   "sampler": {"type": "independent", "sample_count": int(spp)}},
    }
    if cam.projection == "orthographic":
        if cam.aperture > 0.0:
            raise ValueError(f"{scene.name}: an orthographic camera with a lens has no Mitsuba counterpart")
        # Mitsuba's orthographic view is 2 x-scales wide and 2 y-scales / aspect tall.
        half_width = 0.5 * cam.ortho_height * width / height
        result["sensor"].update(type="orthographic", to_world=result["sensor"]["to_world"] @ T().scale(
            [half_width, half_width, 1.0]))
        del result["sensor"]["fov"], result["sensor"]["fov_axis"]
    elif cam.aperture > 0.0:
        result["sensor"].update(type="thinlens", aperture_radius=float(cam.aperture),
                                focus_distance=float(cam.focus_distance))
    environment = _environment(scene, T)
    if environment is not None:
        result["environment"] = environment
    for k, light in enumerate(scene.lights):
        result[f"light_{k}"] = _light(light, T)
    assembly = assemble(scene, instancing=False)  # every triangle placed in the world
    media = {m.name: m for m in scene.media}
    bsdfs = [_sided(_bsdf(m, notes), m) if isinstance(m, MaterialSpec) else _gltf_bsdf(m, notes)
             for m in assembly.materials]
    emission = [m.emission if isinstance(m, MaterialSpec) else tuple(m.pbr.emissive_factor)
                for m in assembly.materials]
    for m in assembly.materials:
        if isinstance(m, MaterialSpec) and m.two_sided_emission and max(m.emission) > 0.0:
            raise ValueError(f"material '{m.name}': emission from both faces has no Mitsuba counterpart "
                             "(its area lights emit from the front)")
    if any(isinstance(m, ModelMaterial) and m.medium is not None for m in assembly.materials):
        notes.append("glTF volume absorption left out")
    data = assembly.data

    # Mitsuba's path leaves a medium for the shape's interior or exterior only where they are set:
    # Lantern's outside is the scene's medium unless the material names one.
    scene_medium = scene.fog.medium if scene.fog.model == "medium" else ""
    if scene_medium:
        result["sensor"]["medium"] = _medium(media[scene_medium])
    sides = [(m.medium, m.outside_medium or scene_medium) if isinstance(m, MaterialSpec) else ("", scene_medium)
             for m in assembly.materials]
    if scene_medium or any(any(pair) for pair in sides):
        result["integrator"]["type"] = "volpath"  # (Mitsuba's path ignores media)

    def add(key, shape, material):
        shape["bsdf"] = bsdfs[material]
        if max(emission[material]) > 0.0:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": list(map(float, emission[material]))}}
        for side, name in zip(("interior", "exterior"), sides[material]):
            if name:
                shape[side] = _medium(media[name])
        result[key] = shape

    for material in np.unique(data.tri_material):
        ply = _mesh_file(mi, data, data.tri_material == material, Path(mesh_dir) / f"mesh_{material}.ply")
        add(f"mesh_{material}", {"type": "ply", "filename": str(ply)}, int(material))
    for k, (sphere, material) in enumerate(zip(data.spheres, data.sphere_material)):
        add(f"sphere_{k}", {"type": "sphere", "center": [float(x) for x in sphere[:3]], "radius": float(sphere[3])},
            int(material))
    for k, (quad, material) in enumerate(zip(data.quads, data.quad_material)):
        add(f"quad_{k}", {"type": "rectangle", "to_world": _rectangle_frame(T, quad)}, int(material))
    for k, (disc, material) in enumerate(zip(data.discs, data.disc_material)):
        add(f"disc_{k}", {"type": "disk", "to_world": _disk_frame(T, disc)}, int(material))
    if len(notes) > NOTE_LIMIT:
        notes = notes[:NOTE_LIMIT] + [f"and {len(notes) - NOTE_LIMIT} more"]
    return result, list(dict.fromkeys(notes))


def _environment(scene: Scene, T) -> dict | None:
    env = scene.environment
    if env.intensity <= 0.0:
        return None
    if env.kind == "constant":
        if max(env.color) <= 0.0:
            return None
        return {"type": "constant", "radiance": {"type": "rgb", "value": [c * env.intensity for c in env.color]}}
    if env.kind == "map":
        angle = env.y_rotation()
        if angle is not None:
            return {"type": "envmap", "filename": str(env.file), "scale": float(env.intensity),
                    "to_world": T().rotate(axis=[0, 1, 0], angle=float(angle))}
        m = np.eye(4)
        m[:3, :3] = env.rotation_matrix()  # the environment's frame to the world's, as Mitsuba's to_world
        return {"type": "envmap", "filename": str(env.file), "scale": float(env.intensity), "to_world": T(m.tolist())}
    raise ValueError(f"{scene.name}: the procedural sky environment has no Mitsuba counterpart")


def _rfilter(render) -> dict:
    if render.pixel_filter == "tent":
        return {"type": "tent", "radius": float(render.filter_radius)}
    if render.pixel_filter == "gaussian":
        return {"type": "gaussian", "stddev": float(render.filter_stddev)}
    return {"type": "box"}


def _light(light, T) -> dict:
    """Point, spot, directional and projector lights as Mitsuba's (the same intensity, irradiance,
    profile and projected image)."""
    if light.kind == "point":
        return {"type": "point", "position": list(map(float, light.position)), "intensity": _rgb(light.intensity)}
    if light.kind == "directional":
        return {"type": "directional", "direction": list(map(float, light.direction)),
                "irradiance": _rgb(light.irradiance)}
    from renderer.lights.light_projection import light_frame

    position = np.asarray(light.position, np.float64)
    to_world = T().look_at(origin=position.tolist(), target=(position + light_frame(light)[2]).tolist(),
                           up=light_frame(light)[1].tolist())
    if light.kind == "spot":
        spot = {"type": "spot", "intensity": _rgb(light.intensity), "cutoff_angle": float(light.cutoff_angle),
                "beam_width": float(light.beam), "to_world": to_world}
        if light.texture is not None:
            spot["texture"] = _image(light.texture)
        return spot
    irradiance = _rgb(light.irradiance) if light.texture is None else _image(light.texture)
    scale = 1.0 if light.texture is None else float(light.irradiance[0])
    if light.texture is not None and len(set(light.irradiance)) > 1:
        raise ValueError("a textured projector with a coloured irradiance has no Mitsuba counterpart")
    return {"type": "projector", "irradiance": irradiance, "scale": scale, "fov": float(light.fov),
            "fov_axis": light.fov_axis, "to_world": to_world}


def _image(texture) -> dict:
    """A light's image as Mitsuba's bitmap texture."""
    if texture.kind != "bitmap" or texture.transform != ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)):
        raise ValueError("only an untransformed bitmap on a light has a Mitsuba counterpart here")
    return {"type": "bitmap", "filename": str(texture.file), "raw": not texture.srgb, "wrap_mode": texture.wrap,
            "filter_type": "nearest" if texture.nearest else "bilinear"}


def _colour(factor, texture) -> dict:
    """A diffuse reflectance: the factor, or Mitsuba's bitmap or checkerboard (with the same uv
    transform, Lantern's TextureSpec being Mitsuba's) where the factor is white."""
    if texture is None:
        return _rgb(factor)
    if tuple(factor) != (1.0, 1.0, 1.0):
        raise ValueError("a texture times a colour other than white has no Mitsuba counterpart here")
    from renderer.bench.mitsuba_side import _import_mitsuba

    mi = _import_mitsuba()[0]
    to_uv = mi.ScalarTransform3f([list(row) for row in texture.transform])
    if texture.kind == "checkerboard":
        return {"type": "checkerboard", "color0": _rgb(texture.color0), "color1": _rgb(texture.color1), "to_uv": to_uv}
    if texture.kind == "bitmap":
        return {"type": "bitmap", "filename": str(texture.file), "raw": not texture.srgb, "wrap_mode": texture.wrap,
                "filter_type": "nearest" if texture.nearest else "bilinear", "to_uv": to_uv}
    if texture.kind in ("mix", "product"):  # Mitsuba has no such texture: the image Lantern bakes
        from renderer.scene.limits import MemoryBudget, MemoryLedger
        from renderer.scene.texture_images import texture_image

        pixels = texture_image(texture, MemoryLedger(MemoryBudget.from_settings())).pixels[..., :3]
        return {"type": "bitmap", "bitmap": mi.Bitmap(np.ascontiguousarray(pixels)), "raw": True,
                "wrap_mode": texture.wrap, "filter_type": "nearest" if texture.nearest else "bilinear",
                "to_uv": to_uv}
    raise ValueError(f"a {texture.kind} texture has no Mitsuba counterpart here")


def _rgb(value) -> dict:
    return {"type": "rgb", "value": [float(c) for c in value]}


def _bsdf(spec: MaterialSpec, notes: list[str]) -> dict:
    alpha = float(spec.roughness) ** 2  # Lantern's perceptual roughness, Mitsuba's GGX alpha
    if spec.base_color_texture is not None and spec.kind != "diffuse":
        notes.append(f"material '{spec.name}': its texture is left out")
    if spec.alpha_texture is not None or spec.alpha_v_texture is not None:
        notes.append(f"material '{spec.name}': its textured roughness is left out (a width of {alpha:g} stands in)")
    if spec.normal_map is not None or spec.bump_map is not None:
        notes.append(f"material '{spec.name}': its normal or bump map is left out")
    distribution = "beckmann" if spec.microfacet == "beckmann" else "ggx"
    if spec.microfacet == "ggx" and alpha > 0 and spec.kind in ("conductor", "dielectric"):
        notes.append(f"material '{spec.name}': Mitsuba's GGX masking is separable where Lantern's (as pbrt's) is "
                     "height-correlated: rough lobes differ by a few percent near grazing angles")
    if spec.kind == "diffuse":
        return {"type": "diffuse", "reflectance": _colour(spec.base_color, spec.base_color_texture)}
    if spec.kind == "conductor":
        rough = {"type": "roughconductor", "distribution": distribution, "alpha": alpha} if alpha > 0 else {"type": "conductor"}
        if spec.metal:
            return {**rough, "material": spec.metal}
        if spec.eta is not None:
            return {**rough, "eta": _rgb(spec.eta), "k": _rgb(spec.k)}
        notes.append(f"material '{spec.name}': a conductor given by its colour is compared as a tinted mirror "
                     "(Mitsuba's conductors take eta and k)")
        return {**rough, "material": "none", "specular_reflectance": _rgb(spec.base_color)}
    if spec.kind == "dielectric":
        if spec.thin:
            return {"type": "thindielectric", "int_ior": float(spec.ior), "ext_ior": 1.0}
        glass = ({"type": "roughdielectric", "distribution": distribution, "alpha": alpha} if alpha > 0
                 else {"type": "dielectric"})
        glass.update(int_ior=float(spec.ior), ext_ior=1.0, specular_transmittance=_rgb(spec.base_color))
        return glass
    if spec.kind == "principled":
        if spec.clearcoat > 0 or max(spec.sheen_color) > 0:
            notes.append(f"material '{spec.name}': its glTF clearcoat and sheen layers are not Disney's")
        return {"type": "principledthin" if spec.thin else "principled", "base_color": _rgb(spec.base_color),
                "roughness": float(spec.roughness), "metallic": float(spec.metallic),
                "spec_trans": float(spec.transmission), "eta": max(float(spec.ior), 1.0001)}
    if spec.kind == "null":
        return {"type": "null"}
    raise ValueError(f"material '{spec.name}': kind '{spec.kind}' has no Mitsuba counterpart")


# Mitsuba BSDFs that reflect from the front only; Lantern's two-sided rows shade both faces alike.
_ONE_SIDED = ("diffuse", "roughconductor", "conductor", "plastic", "roughplastic")


def _sided(bsdf: dict, spec: MaterialSpec) -> dict:
    """A two-sided Lantern material as Mitsuba's twosided around its reflective BSDF (pbrt's and
    Lantern's default: the back of a wall shades as its front); "back_black" stays one-sided."""
    if spec.sidedness == "two_sided" and bsdf["type"] in _ONE_SIDED:
        return {"type": "twosided", "bsdf": bsdf}
    return bsdf


def _medium(m) -> dict:
    if m.kind == "grid":  # (its grids would need writing out as .vol files first)
        raise ValueError(f"medium '{m.name}': grid media have no Mitsuba counterpart here yet")
    sigma_t = np.add(m.sigma_a, m.sigma_s)
    albedo = np.divide(m.sigma_s, sigma_t, out=np.zeros(3), where=sigma_t > 0)
    return {"type": "homogeneous", "sigma_t": _rgb(sigma_t), "albedo": _rgb(albedo),
            "phase": {"type": "hg", "g": float(m.g)}}


def _gltf_bsdf(material, notes: list[str]) -> dict:
    pbr = material.pbr
    if pbr.texture_slots:
        notes.append(f"model material '{pbr.name}': its textures are left out (their factors are compared)")
    return {"type": "principled", "base_color": _rgb(pbr.base_color_factor[:3]), "roughness": float(pbr.roughness_factor),
            "metallic": float(pbr.metallic_factor), "spec_trans": float(pbr.transmission_factor),
            "eta": max(float(pbr.ior), 1.0001)}


def _mesh_file(mi, data, mask, path: Path) -> Path:
    """The triangles of one material written as a PLY file (corners not shared, normals kept
    where every corner has one)."""
    corners = np.ascontiguousarray(data.tri_vertices[mask], np.float32).reshape(-1, 3)
    normals = None if data.tri_normals is None else np.asarray(data.tri_normals[mask], np.float32).reshape(-1, 3)
    has_normals = normals is not None and bool(np.all(np.linalg.norm(normals, axis=1) > 0))
    uvs = None if data.tri_uvs is None else np.asarray(data.tri_uvs[mask], np.float32).reshape(-1, 2)
    mesh = mi.Mesh(path.stem, len(corners), len(corners) // 3, has_vertex_normals=has_normals,
                   has_vertex_texcoords=uvs is not None)
    params = mi.traverse(mesh)
    params["vertex_positions"] = corners.ravel()
    params["faces"] = np.arange(len(corners), dtype=np.uint32)
    if has_normals:
        params["vertex_normals"] = normals.ravel()
    if uvs is not None:
        params["vertex_texcoords"] = uvs.ravel()
    params.update()
    mesh.write_ply(str(path))
    return path


def _rectangle_frame(T, quad):
    """Mitsuba's [-1, 1]^2 rectangle (facing +z) onto a quad (corner, edge_u, edge_v) facing edge_u x edge_v."""
    corner, edge_u, edge_v = (np.asarray(v, np.float64) for v in quad)
    normal = np.cross(edge_u, edge_v)
    normal /= np.linalg.norm(normal)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = edge_u / 2, edge_v / 2, normal, corner + (edge_u + edge_v) / 2
    return T(m.tolist())


def _disk_frame(T, disc):
    """Mitsuba's unit disk (facing +z) onto a disc (centre, normal, radius)."""
    centre, normal, radius = np.asarray(disc[:3], np.float64), np.asarray(disc[3:6], np.float64), float(disc[6])
    normal /= np.linalg.norm(normal)
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, normal)
    x /= np.linalg.norm(x)
    y = np.cross(normal, x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x * radius, y * radius, normal, centre
    return T(m.tolist())

"""pbrt-v4 materials, textures and media made into Lantern's MaterialSpec, TextureSpec and
MediumSpec (the material part of scene_builder.py).

Rough lobes: pbrt's roughness r becomes the microfacet width alpha = sqrt(r) with remaproughness
(the default; TrowbridgeReitzDistribution::RoughnessToAlpha), else alpha = r; Lantern's
perceptual roughness is sqrt(alpha). pbrt's masking is height-correlated GGX, Lantern's "ggx".
Texture coordinates: pbrt's v points up an image; Lantern's meshes carry v down (its PLY reader
turns v over, as the reader of inline meshes does), so a texture's (u, v) mapping becomes
u' = su u + du, v' = sv v + 1 - sv - dv.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from renderer.scene.description import MaterialSpec, MediumSpec, TextureSpec, VolumeGridSpec
from renderer.scene.errors import SceneError
from renderer.scene.pbrt.directives import Directive, NamedRef
from renderer.scene.pbrt.parameters import resolve
from renderer.scene.pbrt.scene_warnings import warn, warn_unused
from renderer.scene.pbrt.spectra import (REFLECTANCE, UNBOUNDED, NamedSpectrum, colour, glass_index, metal_of,
                                         sampled)
from renderer.scene.references import missing_file_problem

DEFAULT_REFLECTANCE = 0.5  # pbrt's diffuse
SMOOTH_ALPHA = 1e-3  # pbrt's TrowbridgeReitz is "effectively smooth" below this width
LINEAR_IMAGES = (".exr", ".hdr", ".pfm")  # pbrt reads these as linear; 8-bit images as sRGB


class MaterialReader:
    def __init__(self, parsed, builder):
        self.parsed, self.builder = parsed, builder
        self.named: dict[str, MaterialSpec] = {}  # pbrt name -> spec (added to the builder's list)
        self.anonymous: dict[int, MaterialSpec] = {}
        self.media: dict[str, str] = {}  # pbrt medium name -> Lantern medium name ("" left out)
        self.mixing: list[str] = []
        self.surfaces: dict[tuple, str] = {}
        self.textures: dict[tuple, tuple] = {}
        self.default: MaterialSpec | None = None  # pbrt's material where a shape has none

    # --- materials ------------------------------------------------------------------------------

    def of_shape(self, ref) -> MaterialSpec:
        """The spec of a shape's current material (pbrt's default: diffuse 0.5)."""
        if ref is None:
            return self._default()
        if isinstance(ref, NamedRef):
            return self.named_spec(ref.name, ref)
        if id(ref) not in self.anonymous:
            self.anonymous[id(ref)] = self._add(self.build(ref, f"{ref.type}{len(self.builder.materials)}"))
        return self.anonymous[id(ref)]

    def named_spec(self, name: str, at) -> MaterialSpec:
        if name not in self.named:
            d = self.parsed.named_materials.get(name)
            if d is None:
                raise SceneError(at.file, f"line {at.line}: no material named '{name}' (MakeNamedMaterial)")
            if name in self.mixing:
                raise d.error(f"mix '{name}' contains itself")
            self.mixing.append(name)
            spec = self.build(d, name)
            self.mixing.pop()
            self.named[name] = self._add(spec)
        return self.named[name]

    def _default(self) -> MaterialSpec:
        if self.default is None:
            self.default = self._add(MaterialSpec("default", "diffuse", base_color=(DEFAULT_REFLECTANCE,) * 3))
        return self.default

    def _add(self, spec: MaterialSpec) -> MaterialSpec:
        taken = {m.name for m in self.builder.materials}
        if spec.name in taken:
            spec = replace(spec, name=next(f"{spec.name}#{k}" for k in range(2, len(taken) + 3)
                                           if f"{spec.name}#{k}" not in taken))
        self.builder.materials.append(spec)
        return spec

    def build(self, d: Directive, name: str) -> MaterialSpec:
        t = d.type
        if t == "diffuse":
            rgb, texture = self.colour(d, "reflectance", DEFAULT_REFLECTANCE)
            spec = MaterialSpec(name, "diffuse", base_color=rgb, base_color_texture=texture)
        elif t == "conductor":
            spec = self.conductor(d, name, "")
        elif t in ("dielectric", "thindielectric"):
            eta = self.eta(d, "eta", 1.5)
            lobe = self.lobe(d) if t == "dielectric" else {"roughness": 0.0}
            spec = MaterialSpec(name, "dielectric", base_color=(1.0, 1.0, 1.0), ior=eta, thin=t == "thindielectric",
                                **lobe)
        elif t in ("interface", "", "none"):
            spec = MaterialSpec(name, "null")
        elif t == "mix":
            spec = self.mix(d, name)
        elif t == "diffusetransmission":
            scale = self.number(d, "scale", 1.0)
            rgb, texture = self.colour(d, "reflectance", 0.25)
            trgb, ttexture = self.colour(d, "transmittance", 0.25)
            spec = MaterialSpec(name, "diffuse_transmission", base_color=tuple(scale * c for c in rgb),
                                base_color_texture=texture, transmittance=tuple(scale * c for c in trgb),
                                parameter_textures=(("transmittance", ttexture),) if ttexture is not None else ())
        elif t == "coateddiffuse":
            rgb, texture = self.colour(d, "reflectance", DEFAULT_REFLECTANCE)
            spec = MaterialSpec(name, "coated", coat_base="diffuse", base_color=rgb, base_color_texture=texture,
                                ior=self.interface_eta(d, "eta"), **self.coat_lobe(d, ""), **self.slab(d))
        elif t == "coatedconductor":
            base = self.conductor(d, name, "conductor.")
            if base.roughness_v is not None:
                warn(d, "an anisotropic conductor under a coat is not supported: its u roughness is used")
            spec = MaterialSpec(name, "coated", coat_base="conductor", ior=self.interface_eta(d, "interface.eta"),
                                metal=base.metal, eta=base.eta, k=base.k,
                                conductor_roughness=(base.roughness if base.alpha_texture is None else
                                                     _untextured(d, {"alpha_texture": base.alpha_texture},
                                                                 "the base conductor's")),
                                **self.coat_lobe(d, "interface."), **self.slab(d))
        else:
            warn(d, f"the {t} material is not supported: rendered as diffuse {DEFAULT_REFLECTANCE:g}")
            spec = MaterialSpec(name, "diffuse", base_color=(DEFAULT_REFLECTANCE,) * 3)
        d.params.find("type")  # a named material's own type
        warn_unused(d)
        return spec

    def conductor(self, d: Directive, name: str, prefix: str) -> MaterialSpec:
        params = d.params
        lobe = self.lobe(d, prefix)
        if params.has("reflectance"):  # pbrt: eta 1 and k from it, so the Fresnel at normal incidence is it
            rgb, texture = self.colour(d, "reflectance", 1.0)
            if texture is None:  # pbrt's own index for it: exact Fresnel from eta = 1, k = 2 sqrt(r / (1 - r))
                r = np.minimum(np.asarray(rgb, np.float64), 0.9999)
                k = tuple(float(x) for x in 2.0 * np.sqrt(r) / np.sqrt(1.0 - r))
                return MaterialSpec(name, "conductor", eta=(1.0, 1.0, 1.0), k=k, **lobe)
            warn(d, "a textured conductor reflectance is drawn with Schlick's Fresnel from it")
            return MaterialSpec(name, "conductor", base_color=rgb, base_color_texture=texture, **lobe)
        eta = self.spectrum(d, prefix + "eta", NamedSpectrum("metal-Cu-eta"))
        k = self.spectrum(d, prefix + "k", NamedSpectrum("metal-Cu-k"))
        if isinstance(eta, NamedSpectrum) or isinstance(k, NamedSpectrum):
            names = [s for s in (eta, k) if isinstance(s, NamedSpectrum)]
            metals = [metal_of(s) for s in names]
            if None in metals:
                warn(d, f"the spectrum '{names[metals.index(None)]}' is not one of Lantern's metals: rendered as Cu")
                metals = ["Cu"]
            if len(names) < 2 or len(set(metals)) > 1:
                warn(d, f"eta and k are not one named metal's pair: rendered as {metals[0]}")
            return MaterialSpec(name, "conductor", metal=metals[0], **lobe)
        return MaterialSpec(name, "conductor", eta=eta, k=k, **lobe)

    def coat_lobe(self, d: Directive, prefix: str) -> dict:
        """A coat's interface roughness (the coated kind's roughness and roughness_v)."""
        lobe = self.lobe(d, prefix)
        if "alpha_texture" in lobe:
            return {"roughness": _untextured(d, lobe, "the coat's"), "roughness_v": None}
        return {"roughness": lobe["roughness"], "roughness_v": lobe.get("roughness_v")}

    def interface_eta(self, d: Directive, name: str) -> float:
        """A coat's index: pbrt takes an eta of 0 as 1 (no interface)."""
        eta = self.eta(d, name, 1.5)
        if eta < 0.0:
            raise d.error(f"{name} {eta:g} is negative")
        return 1.0 if eta == 0.0 else eta

    def slab(self, d: Directive) -> dict:
        """The coated kind's slab between the interface and the base: pbrt's thickness, the albedo and
        g of the medium in it, and its random walks' depth and count."""
        albedo, texture = self.colour(d, "albedo", 0.0)
        if texture is not None:
            warn(d, "a texture on 'albedo' is not supported: its mean is not known here, black is used")
            albedo = (0.0, 0.0, 0.0)
        thickness, g = self.number(d, "thickness", 0.01), self.number(d, "g", 0.0)
        depth, samples = int(self.number(d, "maxdepth", 10)), int(self.number(d, "nsamples", 1))
        if thickness <= 0.0 or not -1.0 < g < 1.0 or depth < 1 or samples < 1:
            raise d.error("a coat needs thickness > 0, -1 < g < 1, maxdepth >= 1 and nsamples >= 1")
        return {"coat_thickness": thickness, "coat_albedo": albedo, "coat_g": g, "coat_maxdepth": depth,
                "coat_nsamples": samples}

    def lobe(self, d: Directive, prefix: str = "") -> dict:
        """roughness (and roughness_v where it differs) from pbrt's roughness or u/vroughness."""
        remap = d.params.boolean("remaproughness", True)  # never prefixed (coatedconductor)
        names = [prefix + n for n in ("roughness", "uroughness", "vroughness")]
        if any(p is not None and p.type == "texture" for p in (d.params.find(n) for n in names)):
            return self.textured_lobe(d, names, remap)
        r = self.number(d, prefix + "roughness", 0.0)
        u, v = self.number(d, prefix + "uroughness", r), self.number(d, prefix + "vroughness", r)
        if min(u, v) < 0:
            raise d.error("a roughness is negative")
        au, av = (math.sqrt(x) if remap else x for x in (u, v))
        if max(au, av) < SMOOTH_ALPHA:
            return {"roughness": 0.0}
        return {"roughness": math.sqrt(au), "roughness_v": math.sqrt(av) if av != au else None, "microfacet": "ggx"}

    def textured_lobe(self, d: Directive, names: list[str], remap: bool) -> dict:
        """A lobe whose width is a texture (Lantern's alpha_texture and alpha_v_texture, alpha itself;
        the constant roughness then only marks the lobe rough): a checkerboard's two widths remapped
        as pbrt remaps, an image's texels as they are where pbrt does not remap them."""
        rough, u_name, v_name = names
        base = self.width(d, rough, 0.0, remap)
        u = self.width(d, u_name, None, remap) if d.params.has(u_name) else base
        v = self.width(d, v_name, None, remap) if d.params.has(v_name) else base
        as_texture = [w if isinstance(w, TextureSpec) else TextureSpec.constant(w) for w in (u, v)]
        return {"roughness": 0.5, "microfacet": "ggx", "alpha_texture": as_texture[0],
                "alpha_v_texture": as_texture[1] if v is not u else None}

    def width(self, d: Directive, name: str, default, remap: bool):
        """pbrt's roughness parameter `name` as Lantern's width alpha: a number or a TextureSpec."""
        p = d.params.find(name)
        if p is None:
            return default
        if p.type != "texture":
            value = self.number(d, name, 0.0)
            return math.sqrt(value) if remap else value
        (factor, _, _), texture = self.texture(p.values[0], p, (0.0, 0.0, 0.0))
        if texture is None:  # a constant or scaled number
            return math.sqrt(factor) if remap else factor
        if texture.kind == "checkerboard":
            widths = [factor * c[0] for c in (texture.color0, texture.color1)]
            widths = [math.sqrt(w) if remap else w for w in widths]
            return replace(texture, color0=(widths[0],) * 3, color1=(widths[1],) * 3)
        if remap or factor != 1.0:
            warn(d, f"'{name}': an image of roughness is read as widths only as it stands (remaproughness false, "
                    "no scale): 0.5 is used")
            return math.sqrt(0.5) if remap else 0.5
        return texture

    def mix(self, d: Directive, name: str) -> MaterialSpec:
        p = d.params.find("materials", ("string",))
        if p is None or len(p.values) != 2:
            raise d.error("needs \"string materials\" naming two materials")
        parts = tuple(self.named_spec(n, d) for n in p.values)
        given = d.params.find("amount")
        if given is not None and given.type == "texture":  # its first channel times mix_weight
            (amount, _, _), texture = self.texture(given.values[0], given, (0.5,) * 3)
            textures = () if texture is None else (("mix_weight", texture),)
        else:
            amount, textures = self.number(d, "amount", 0.5), ()
        if not 0.0 <= amount <= 1.0:
            raise d.error(f"amount {amount:g} is not between 0 and 1")
        return MaterialSpec(name, parts[0].kind, mix=parts, mix_weight=amount, parameter_textures=textures)

    # --- values ---------------------------------------------------------------------------------

    def number(self, d: Directive, name: str, default: float) -> float:
        p = d.params.find(name)
        if p is None:
            return default
        if p.type == "texture":
            warn(d, f"a texture on '{name}' is not supported: {default:g} is used")
            return default
        if p.type not in ("float", "integer") or len(p.values) != 1:
            raise p.error("expected one number")
        return float(p.values[0])

    def eta(self, d: Directive, name: str, default: float) -> float:
        p = d.params.find(name)
        if p is None:
            return default
        if p.type == "spectrum":  # one index: the spectrum's at 550 nm (no dispersion)
            if isinstance(colour(p, UNBOUNDED), NamedSpectrum):
                index = glass_index(p.values[0])
                if index is None:
                    warn(d, f"the spectrum '{p.values[0]}' is not a glass Lantern knows: eta {default:g} is used")
                    return default
                return index
            w, v = sampled(p)
            return float(np.interp(550.0, w, v))
        if p.type == "texture":
            warn(d, f"a texture on '{name}' is not supported: {default:g} is used")
            return default
        return float(colour(p, UNBOUNDED)[1])

    def spectrum(self, d: Directive, name: str, default):
        p = d.params.find(name)
        if p is None:
            return default
        if p.type == "texture":
            warn(d, f"a texture on '{name}' is not supported: its default is used")
            return default
        return colour(p, UNBOUNDED)

    def colour(self, d: Directive, name: str, default: float, role: str = REFLECTANCE):
        """(RGB, TextureSpec or None) of a colour parameter that may name a texture."""
        p = d.params.find(name)
        fallback = (float(default),) * 3
        if p is None:
            return fallback, None
        if p.type == "texture":
            return self.texture(p.values[0], p, fallback)
        value = colour(p, role)
        if isinstance(value, NamedSpectrum):
            warn(d, f"the named spectrum '{value}' is not supported on '{name}': {default:g} is used")
            return fallback, None
        return value, None

    def texture(self, name: str, at, fallback) -> tuple:
        """(colour, TextureSpec or None) of a named texture where a colour would be; read once per
        name (and stand-in), so its warnings come once."""
        key = (name, tuple(fallback))
        if key not in self.textures:
            self.textures[key] = self._texture(name, at, fallback)
        return self.textures[key]

    def _texture(self, name: str, at, fallback) -> tuple:
        t = self.parsed.textures.get(name)
        if t is None:
            raise at.error(f"no texture named '{name}'")
        if t.type == "imagemap":
            return self.imagemap(t, fallback)
        if t.type == "checkerboard":
            return self.checkerboard(t, fallback)
        if t.type == "constant":
            value = self.colour(t, "value", 1.0)
            warn_unused(t)
            return value
        if t.type in ("scale", "mix"):
            return self.combined(t)
        warn(t, f"the {t.type} texture is not supported: the parameter is {fallback[0]:g}")
        return fallback, None

    def combined(self, t: Directive) -> tuple:
        """pbrt's `scale` (tex times scale) and `mix` ((1 - amount) tex1 + amount tex2) textures,
        each operand a colour, a number or a texture: a colour where none is a texture, else one
        TextureSpec baked at assembly (renderer/scene/texture_mixing.py)."""
        if t.type == "scale":
            kind, first, second = "product", self.colour(t, "tex", 1.0), self.colour(t, "scale", 1.0)
            amount = (0.5, None)
        else:
            kind, first, second = "mix", self.colour(t, "tex1", 0.0), self.colour(t, "tex2", 1.0)
            (weight, _, _), weight_texture = self.colour(t, "amount", 0.5)
            amount = (weight, weight_texture)
        warn_unused(t)
        textures = [x for x in (first[1], second[1], amount[1]) if x is not None]
        mappings = {(x.transform, x.wrap, x.nearest) for x in textures}
        if len(mappings) > 1:
            warn(t, "its textures have different uv mappings, filters or wraps: the first's are used for all")
        return combined_texture(kind, first, second, amount)

    def mapping(self, t: Directive, checker: bool) -> tuple:
        kind = t.params.string("mapping", "uv")
        if kind != "uv":
            warn(t, f"the {kind} mapping is not supported: the uv mapping is used")
        su, sv = self.number(t, "uscale", 1.0), self.number(t, "vscale", 1.0)
        du, dv = self.number(t, "udelta", 0.0), self.number(t, "vdelta", 0.0)
        if checker:  # Lantern's checkerboard: squares of half a period (pbrt's: of one)
            return ((su / 2, 0.0, du / 2), (0.0, -sv / 2, (sv + dv) / 2), (0.0, 0.0, 1.0))
        return ((su, 0.0, du), (0.0, sv, 1.0 - sv - dv), (0.0, 0.0, 1.0))

    def imagemap(self, t: Directive, fallback) -> tuple:
        filename = t.params.string("filename")
        if filename is None:
            raise t.error("needs a \"string filename\"")
        path = resolve(t.params.find("filename").token, filename)
        transform = self.mapping(t, False)
        scale = self.number(t, "scale", 1.0)
        encoding = t.params.string("encoding", "linear" if path.suffix.lower() in LINEAR_IMAGES else "sRGB")
        if encoding not in ("sRGB", "linear"):
            warn(t, f"encoding '{encoding}' is not supported: read as sRGB")
        if t.params.boolean("invert", False):
            warn(t, "invert is not supported: the image is used as it is")
        wrap = t.params.string("wrap", "repeat")
        if wrap not in ("repeat", "clamp"):
            warn(t, f"wrap '{wrap}' is not supported: repeat is used")
            wrap = "repeat"
        nearest = t.params.string("filter", "bilinear") == "point"
        t.params.find("maxanisotropy")
        warn_unused(t)
        if not path.is_file():
            warn(t, f"{filename}: {missing_file_problem(path)}: {fallback[0]:g} stands in for the image")
            return fallback, None
        self.builder.source_files.append(path)
        return (scale,) * 3, TextureSpec("bitmap", file=path, srgb=encoding != "linear", wrap=wrap, nearest=nearest,
                                         transform=transform)

    def checkerboard(self, t: Directive, fallback) -> tuple:
        if t.params.integer("dimension", 2) != 2:
            warn(t, "a 3D checkerboard is not supported: the parameter is its default")
            return fallback, None
        colours = []
        for name, default in (("tex1", 1.0), ("tex2", 0.0)):
            p = t.params.find(name)
            if p is not None and p.type == "texture":
                warn(t, f"a texture as '{name}' is not supported: {default:g} is used")
                p = None
            value = (default,) * 3 if p is None else colour(p, REFLECTANCE)
            colours.append((default,) * 3 if isinstance(value, NamedSpectrum) else value)
        transform = self.mapping(t, True)
        warn_unused(t)
        return (1.0, 1.0, 1.0), TextureSpec("checkerboard", nearest=True, transform=transform,
                                            color0=colours[0], color1=colours[1])

    # --- media ----------------------------------------------------------------------------------

    def medium(self, name: str, at) -> str:
        """The Lantern medium a pbrt medium name stands for ("" where there is none)."""
        if not name:
            return ""
        if name not in self.media:
            d = self.parsed.media.get(name)
            if d is None:
                warn(at, f"no medium named '{name}' (MakeNamedMedium): there is none")
                self.media[name] = ""
                return ""
            self.media[name] = self._medium(d, name)
        return self.media[name]

    def _medium(self, d: Directive, name: str) -> str:
        if d.type == "uniformgrid":
            return self._grid_medium(d, name)
        if d.type != "homogeneous":
            warn(d, f"the {d.type} medium is not supported: left out")
            d.params.find("type")
            for p in d.params.params:
                p.used = True
            return ""
        d.params.find("type")
        if d.params.has("preset"):
            warn(d, "named scattering presets are not supported: sigma_a and sigma_s are used")
            d.params.find("preset")
        sigma_a, sigma_s, scale, g = self._coefficients(d)
        warn_unused(d)
        self.builder.media.append(MediumSpec(name, sigma_a=tuple(scale * c for c in sigma_a),
                                             sigma_s=tuple(scale * c for c in sigma_s), g=g))
        return name

    def _coefficients(self, d: Directive) -> tuple:
        """(sigma_a, sigma_s, scale, g) of a medium directive, pbrt's defaults 1, 1, 1, 0."""
        sigma = []
        for param in ("sigma_a", "sigma_s"):
            p = d.params.find(param)
            value = (1.0, 1.0, 1.0) if p is None else colour(p, UNBOUNDED)
            if isinstance(value, NamedSpectrum):
                raise p.error(f"the named spectrum '{value}' is not a medium coefficient")
            sigma.append(value)
        scale = self.number(d, "scale", 1.0)
        g = self.number(d, "g", 0.0)
        if not -1.0 < g < 1.0:
            raise d.error(f"g {g:g} is not between -1 and 1")
        return sigma[0], sigma[1], scale, g

    def _grid_medium(self, d: Directive, name: str) -> str:
        """pbrt's uniformgrid as Lantern's grid medium: extinction (sigma_a + sigma_s) scale
        density(p) over the box [p0, p1] of the medium's space (its transform at MakeNamedMedium),
        density at the cell centres read trilinearly as pbrt's SampledGrid; albedo sigma_s /
        (sigma_a + sigma_s) throughout. Emission (Le, temperature) is left out with a warning."""
        d.params.find("type")
        sigma_a, sigma_s, scale, g = self._coefficients(d)
        res = [d.params.integer(axis, 1) for axis in ("nx", "ny", "nz")]
        density = d.params.floats("density")
        if density is None:
            raise d.error("a uniformgrid needs \"float density\" values")
        if min(res) < 1 or len(density) != res[0] * res[1] * res[2]:
            raise d.error(f"{len(density)} density values for a grid of {res[0]} x {res[1]} x {res[2]}")
        values = np.asarray(density, np.float32).reshape(res[2], res[1], res[0], 1)
        if not np.isfinite(values).all() or values.min() < 0.0:
            raise d.error("density values must be finite and not negative")
        p0, p1 = (np.asarray(d.params.point3(k, v), np.float64) for k, v in (("p0", (0, 0, 0)), ("p1", (1, 1, 1))))
        if np.any(p1 <= p0):
            raise d.error("p1 must exceed p0 on every axis")
        for emitted in ("Le", "Lescale", "temperature", "temperaturescale", "temperatureoffset"):
            if d.params.has(emitted):
                d.params.find(emitted)
                warn(d, f"'{emitted}': emission from a medium is not supported: left out")
        warn_unused(d)
        box = np.diag([*(p1 - p0), 1.0])
        box[:3, 3] = p0
        to_world = tuple(tuple(float(v) for v in row) for row in d.ctm @ box)
        extinction = np.add(sigma_a, sigma_s)
        albedo = np.divide(sigma_s, extinction, out=np.zeros(3), where=extinction > 0)
        self.builder.media.append(MediumSpec(
            name, kind="grid", g=g, scale=scale,
            density=VolumeGridSpec(values=values * extinction.astype(np.float32), to_world=to_world),
            albedo=VolumeGridSpec(values=albedo.astype(np.float32).reshape(1, 1, 1, 3), to_world=to_world,
                                  constant=tuple(float(a) for a in albedo))))
        return name


    def alpha(self, d: Directive) -> tuple:
        """(opacity, its texture or None) of a shape's `alpha`: a number, or a float texture whose
        first channel is the coverage (pbrt's alpha test, Lantern's stochastic opacity)."""
        p = d.params.find("alpha")
        if p is None:
            return 1.0, None
        if p.type == "texture":
            rgb, texture = self.texture(p.values[0], p, (1.0, 1.0, 1.0))
            return float(rgb[0]), texture
        if p.type != "float" or len(p.values) != 1 or not 0.0 <= float(p.values[0]) <= 1.0:
            raise p.error("alpha must be one number in [0, 1] or a float texture")
        return float(p.values[0]), None

    def with_surface(self, base: MaterialSpec, emission, medium: str, outside: str = "",
                     alpha: tuple = (1.0, None), two_sided: bool = False) -> str:
        """The name of `base` with a shape's emission, interior medium, outside medium and alpha
        (a material of its own, shared by the shapes that have the same)."""
        opacity, opacity_texture = alpha
        cut = opacity < 1.0 or opacity_texture is not None
        if max(emission) <= 0.0 and not medium and not outside and not cut:
            return base.name
        two_sided = two_sided and max(emission) > 0.0
        key = (base.name, tuple(emission), medium, outside, opacity, id(opacity_texture), two_sided)
        if key not in self.surfaces:
            parts = ("emitter" if max(emission) > 0.0 else "", medium, f"in {outside}" if outside else "",
                     "alpha" if cut else "")
            suffix = "+".join(part for part in parts if part)
            spec = replace(base, name=f"{base.name}+{suffix}", emission=tuple(emission), two_sided_emission=two_sided,
                           medium=medium,
                           outside_medium=outside, opacity=opacity if cut else base.opacity,
                           opacity_texture=opacity_texture if cut else base.opacity_texture)
            self.surfaces[key] = self._add(spec).name
        return self.surfaces[key]


def _untextured(d: Directive, lobe: dict, whose: str) -> float:
    """The one roughness a coated material's lobe can have where pbrt's is a texture (with a
    warning): a checkerboard's mean width, else smooth."""
    texture = lobe["alpha_texture"]
    alpha = 0.5 * (texture.color0[0] + texture.color1[0]) if texture.kind == "checkerboard" else 0.0
    warn(d, f"{whose} textured roughness is not supported under a coat: "
            + (f"its mean width {alpha:g} is used" if alpha > 0.0 else "it is smooth"))
    return math.sqrt(alpha)



def combined_texture(kind: str, first: tuple, second: tuple, amount: tuple = (0.5, None)) -> tuple:
    """(colour, TextureSpec or None) of a product or mix of two (colour, texture or None)
    operands; a texture only where one is needed (a texture times colours stays that texture)."""
    (c1, t1), (c2, t2), (a, ta) = first, second, amount
    if kind == "product" and (t1 is None or t2 is None):
        return tuple(x * y for x, y in zip(c1, c2)), t1 or t2
    if kind == "mix" and ta is None:
        if t1 is None and t2 is None:
            return tuple((1.0 - a) * x + a * y for x, y in zip(c1, c2)), None
        if t2 is None and not any(c2):
            return tuple((1.0 - a) * x for x in c1), t1
        if t1 is None and not any(c1):
            return tuple(a * y for y in c2), t2
    shape = next(x for x in (t1, t2, ta) if x is not None)
    operands = ((tuple(map(float, c1)), t1), (tuple(map(float, c2)), t2))
    return (1.0, 1.0, 1.0), TextureSpec(kind, operands=operands, amount=(float(a), ta), transform=shape.transform,
                                        wrap=shape.wrap, nearest=shape.nearest)

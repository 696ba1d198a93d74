"""pbrt-v4's colour parameters made RGB: "rgb" as written; "spectrum" (wavelength-value pairs, a
file of them, or a named spectrum) and "blackbody" integrated against the CIE curves as the
Mitsuba reader does (renderer/spectral/mitsuba_rgb.py). Light spectra other than RGB are
normalised to luminance 1, as pbrt-v4 divides every light's spectrum by its photometric
integral (an RGB light's spectrum is the colour space's illuminant, which that division makes
white of luminance 1)."""
from __future__ import annotations

import numpy as np

from renderer.materials.metals import metal_names
from renderer.scene.pbrt.parameters import Param, resolve
from renderer.spectral.ior import sellmeier_ior_np
from renderer.spectral.mitsuba_rgb import spectrum_to_rgb

REFLECTANCE, UNBOUNDED, ILLUMINANT = "reflectance", "unbounded", "illuminant"
REC709_LUMINANCE = (0.2126, 0.7152, 0.0722)
# Schott's Sellmeier coefficients (B, C in um^2) of the glasses pbrt-v4 names glass-*.
GLASSES = {
    "glass-BK7": ((1.03961212, 0.231792344, 1.01046945), (0.00600069867, 0.0200179144, 103.560653)),
    "glass-BAF10": ((1.5851495, 0.143559385, 1.08521269), (0.00926681282, 0.0424489805, 105.613573)),
    "glass-FK51A": ((0.971247817, 0.216901417, 0.904651666), (0.00472301995, 0.0153575612, 168.68133)),
    "glass-LASF9": ((2.00029547, 0.298926886, 1.80691843), (0.0121426017, 0.0538736236, 156.530829)),
    "glass-F5": ((1.52481889, 0.187085527, 1.42729015), (0.011254756, 0.0588995392, 129.141675)),
    "glass-F10": ((1.62153902, 0.256287842, 1.64447552), (0.0122241457, 0.0595736775, 147.468793)),
    "glass-F11": ((1.73759695, 0.313747346, 1.89878101), (0.013188707, 0.0623068142, 155.23629)),
}
WHITE_ILLUMINANTS = ("stdillum-D65", "illum-D65")


class NamedSpectrum(str):
    """A spectrum given by pbrt-v4's name (metal-Cu-eta, glass-BK7, ...), for the mapping to read."""


def luminance(rgb) -> float:
    return float(np.dot(REC709_LUMINANCE, rgb))


def glass_index(name: str) -> float | None:
    """A named glass's index of refraction at 550 nm (Lantern's dielectrics take one index)."""
    if name not in GLASSES:
        return None
    b, c = GLASSES[name]
    return float(sellmeier_ior_np(np.array([550.0]), (*b, 0.0), (*c, 0.0))[0])


def metal_of(name: str) -> str | None:
    """The Lantern metal of a named spectrum metal-X-eta or metal-X-k (None if not one Lantern has)."""
    parts = name.split("-")
    if len(parts) != 3 or parts[0] != "metal" or parts[2] not in ("eta", "k"):
        return None
    known = {m.lower(): m for m in metal_names()}
    return known.get(parts[1].lower())


def blackbody_rgb(kelvin: float) -> tuple:
    """A blackbody's colour at luminance 1."""
    w = np.linspace(360.0, 830.0, 95)
    m = w * 1e-9
    planck = 1.0 / (m ** 5 * (np.exp(1.4387769e-2 / (m * kelvin)) - 1.0))
    rgb = np.array(spectrum_to_rgb(w, planck / planck.max(), bounded=False, d65=False))
    return tuple(float(x) for x in rgb / luminance(rgb))


def sampled(param: Param) -> tuple[np.ndarray, np.ndarray]:
    """The (wavelengths, values) of a "spectrum" parameter given as numbers or a file of them."""
    if param.values and isinstance(param.values[0], str):
        path = resolve(param.token, param.values[0])
        try:
            text = path.read_text()
        except OSError as e:
            raise param.error(f"cannot read the spectrum file {path}: {e.strerror or e}") from None
        numbers = []
        for line in text.splitlines():
            line = line.split("#", 1)[0]
            try:
                numbers += [float(x) for x in line.replace(",", " ").split()]
            except ValueError:
                raise param.error(f"{path.name} holds something other than numbers") from None
    else:
        numbers = [float(v) for v in param.values]
    if len(numbers) < 4 or len(numbers) % 2:
        raise param.error("a spectrum needs wavelength-value pairs, at least two")
    pairs = np.array(numbers).reshape(-1, 2)
    if np.any(np.diff(pairs[:, 0]) <= 0):
        raise param.error("a spectrum's wavelengths must increase")
    return pairs[:, 0], pairs[:, 1]


def colour(param: Param, role: str):
    """RGB of a colour parameter in `role` (REFLECTANCE: under D65, clamped to [0, 1]; UNBOUNDED: an
    index or medium coefficient; ILLUMINANT: a light's, normalised as pbrt normalises it), or a
    NamedSpectrum for a named spectrum other than an illuminant's white."""
    if param.type in ("rgb", "color"):
        if len(param.values) != 3:
            raise param.error("expected 3 numbers")
        return tuple(float(v) for v in param.values)
    if param.type in ("float", "integer"):
        if len(param.values) != 1:
            raise param.error("expected one number")
        return (float(param.values[0]),) * 3
    if param.type == "blackbody":
        if len(param.values) not in (1, 2) or param.values[0] <= 0:
            raise param.error("expected a temperature in kelvin")
        return blackbody_rgb(param.values[0])
    if param.type != "spectrum":
        raise param.error("expected a colour (rgb, spectrum or blackbody)")
    if len(param.values) == 1 and isinstance(param.values[0], str):
        name = param.values[0]
        if name in WHITE_ILLUMINANTS:
            return (1.0, 1.0, 1.0)
        if name.startswith(("metal-", "glass-", "canon_", "nikon_", "sony_", "stdillum-", "illum-")):
            return NamedSpectrum(name)
    w, v = sampled(param)
    if role == ILLUMINANT:
        rgb = np.array(spectrum_to_rgb(w, v, bounded=False, d65=False))
        y = luminance(rgb)
        return tuple(float(x) for x in rgb / y) if y > 0 else (0.0, 0.0, 0.0)
    if role == UNBOUNDED:  # indices and coefficients: a constant stays itself (no white point's tint)
        return (float(v[0]),) * 3 if np.allclose(v, v[0]) else spectrum_to_rgb(w, v, bounded=False, d65=False)
    return spectrum_to_rgb(w, v, bounded=True, d65=True)

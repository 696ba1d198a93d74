"""Derives the RGB complex indices of refraction (eta, k) of the named metals (`metal = "Au"` on a
`conductor`) from published measured spectra, the way Mitsuba 3's RGB variants turn a material
preset into RGB, and writes renderer/materials/data/metals.csv.

Where the spectra come from
    * Every preset Mitsuba 3 ships (`<name>.eta.spd` and `<name>.k.spd` in the `ior/` folder of
      the mitsuba-data repository, https://github.com/mitsuba-renderer/mitsuba-data, which Mitsuba 3
      checks out as resources/data). They are the spectra pbrt distributes too, originally from the
      Luxpop database: Palik's handbook of optical constants and CXRO/LLNL atomic scattering
      factors. Lines hold "wavelength_nm value"; '#' starts a comment.
    * Four metals Mitsuba has no (or only a Palik) preset for, from the refractiveindex.info
      database (https://github.com/polyanskiy/refractiveindex.info-database, CC0; files
      database/data/main/<metal>/nk/<file>.yml, "tabulated nk" in micrometres):
        Fe, Ni, Ti: Johnson and Christy 1974, Phys. Rev. B 9, 5056 (measured; nk/Johnson.yml);
        Pt: Rakic et al. 1998, Appl. Opt. 37, 5271 (their Brendel-Bormann fit of measured data,
            tabulated; nk/Rakic-BB.yml); Johnson and Christy did not measure platinum.
    * The CIE 1931 colour matching functions: renderer/spectral/data/cie1931_d65_5nm.csv.

How Mitsuba 3 makes RGB of a spectrum: include/mitsuba/render/ior.h `ior_from_file` calls
`spectrum_list_to_srgb(wavelengths, values, bounded=false, d65=false)`, reproduced by
renderer/spectral/mitsuba_rgb.py (its docstring gives the rule), which the Mitsuba scene reader
uses too. No illuminant enters: each of eta and k is a plain spectrum.

Usage:
    python scripts/make_metal_table.py --mitsuba-ior PATH/mitsuba-data/ior \
        --refractiveindex PATH/refractiveindex.info-database/database/data/main
(writes renderer/materials/data/metals.csv; tests/materials/test_metals.py checks a few rows
against the values Mitsuba 3 itself reports).
"""
import argparse
import csv
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from renderer.spectral.mitsuba_rgb import CIE_MAX, CIE_MIN, spectrum_to_rgb  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "renderer" / "materials" / "data" / "metals.csv"
# (name, folder under refractiveindex.info's data/main, file, citation)
EXTRA = (("Fe", "Fe/nk/Johnson.yml", "Johnson and Christy 1974"),
         ("Ni", "Ni/nk/Johnson.yml", "Johnson and Christy 1974"),
         ("Pt", "Pt/nk/Rakic-BB.yml", "Rakic et al. 1998 (Brendel-Bormann fit)"),
         ("Ti", "Ti/nk/Johnson.yml", "Johnson and Christy 1974"))


def metal_rgb(wavelengths, values) -> np.ndarray:
    """An eta or k spectrum as Mitsuba's ior_from_file makes it RGB: unbounded, without D65."""
    return np.array(spectrum_to_rgb(wavelengths, values, bounded=False, d65=False), np.float32)


def read_spd(path: Path):
    wavelengths, values = [], []
    for line in path.read_text().splitlines():
        line = line.split("#", 1)[0].split()
        if len(line) >= 2:
            wavelengths.append(float(line[0]))
            values.append(float(line[1]))
    return wavelengths, values


def read_tabulated_nk(path: Path):
    """A refractiveindex.info 'tabulated nk' block: (nm, n, k) rows."""
    rows, inside = [], False
    for line in path.read_text().splitlines():
        stripped = line.strip()
        if stripped.startswith("- type:"):
            inside = stripped == "- type: tabulated nk"
            continue
        if inside and stripped and not stripped.startswith("data:"):
            parts = stripped.split()
            if len(parts) != 3:
                break
            rows.append([float(p) for p in parts])
    if not rows:
        raise SystemExit(f"error: {path}: no 'tabulated nk' data")
    data = np.array(rows)
    return data[:, 0] * 1000.0, data[:, 1], data[:, 2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mitsuba-ior", type=Path, required=True, help="mitsuba-data's ior/ folder")
    parser.add_argument("--refractiveindex", type=Path, required=True,
                        help="refractiveindex.info-database's database/data/main folder")
    args = parser.parse_args()
    rows = []
    for eta_file in sorted(args.mitsuba_ior.glob("*.eta.spd")):
        name = eta_file.name[:-len(".eta.spd")]
        k_file = eta_file.with_name(f"{name}.k.spd")
        eta_w, eta_v = read_spd(eta_file)
        k_w, k_v = read_spd(k_file)
        source = "Mitsuba 3 preset (Luxpop: Palik; CXRO/LLNL)"
        if eta_w[0] > CIE_MIN or eta_w[-1] < CIE_MAX or k_w[0] > CIE_MIN or k_w[-1] < CIE_MAX:
            source += f"; spectrum covers {min(eta_w[0], k_w[0]):.0f}-{max(eta_w[-1], k_w[-1]):.0f} nm only"
        rows.append((name, metal_rgb(eta_w, eta_v), metal_rgb(k_w, k_v), source))
    for name, file, citation in EXTRA:
        nm, n, k = read_tabulated_nk(args.refractiveindex / file)
        rows.append((name, metal_rgb(nm, n), metal_rgb(nm, k),
                     f"refractiveindex.info: {citation}"))
    rows.sort(key=lambda r: r[0].lower())
    OUT.parent.mkdir(parents=True, exist_ok=True)
    with OUT.open("w", newline="") as f:
        f.write("# Written by scripts/make_metal_table.py (see it for the data and the method). RGB complex\n"
                "# index of refraction eta + i k per metal, from measured spectra as Mitsuba 3's RGB variants\n"
                "# convert them (float32 values, printed to 9 significant digits).\n")
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(["name", "eta_r", "eta_g", "eta_b", "k_r", "k_g", "k_b", "source"])
        for name, eta, k, source in rows:
            writer.writerow([name, *(f"{float(x):.9g}" for x in eta), *(f"{float(x):.9g}" for x in k), source])
    print(f"wrote {len(rows)} metals to {OUT}")


if __name__ == "__main__":
    main()

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
    * The CIE 1931 2-degree colour matching functions, 360-830 nm: the CIE's own table (CIE
      015:2018, dataset DOI 10.25039/CIE.DS.xvudnb9b, file CIE_xyz_1931_2deg.csv: lines
      "nm,x,y,z" at 1 nm); Mitsuba stores its rows at every 5 nm as float32.

How Mitsuba 3 makes RGB of a spectrum (include/mitsuba/render/ior.h `ior_from_file` calls
src/core/spectrum.cpp `spectrum_list_to_srgb(wavelengths, values, bounded=false, d65=false)`),
reproduced by `spectrum_to_rgb` below:
    * 1000 wavelengths w_i = 360 + 470 i / 999 nm; those outside the spectrum's first and last
      wavelength are skipped (they add 0: a spectrum that stops at 590 nm loses its red);
    * the spectrum is interpolated linearly between its samples, the CMFs linearly between the
      5 nm rows of the table (as float32);
    * XYZ = sum cmf(w_i) value(w_i) * 470 / 1000 / 106.7502593994140625 (Mitsuba's
      MI_CIE_Y_NORMALIZATION), in double precision;
    * RGB = the XYZ -> linear sRGB (Rec. 709) matrix of include/mitsuba/core/spectrum.h, with its
      float32 coefficients, and negative channels clamped to 0; stored as float32.
No white point or illuminant enters: each of eta and k is treated as a plain spectrum, so RGB
(1, 1, 1) is the constant spectrum 1 integrated against unit-area CMFs.

Usage:
    python scripts/make_metal_table.py --mitsuba-ior PATH/mitsuba-data/ior \
        --refractiveindex PATH/refractiveindex.info-database/database/data/main \
        --cie PATH/CIE_xyz_1931_2deg.csv
(writes renderer/materials/data/metals.csv; tests/materials/test_metals.py checks a few rows
against the values Mitsuba 3 itself reports).
"""
import argparse
import csv
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parents[1] / "renderer" / "materials" / "data" / "metals.csv"
CIE_MIN, CIE_MAX, CIE_SAMPLES = 360.0, 830.0, 95
STEPS = 1000
Y_NORMALIZATION = 1.0 / 106.7502593994140625
XYZ_TO_SRGB = np.array([[3.240479, -1.537150, -0.498535],
                        [-0.969256, 1.875991, 0.041556],
                        [0.055648, -0.204043, 1.057311]], np.float32).astype(np.float64)
# (name, folder under refractiveindex.info's data/main, file, citation)
EXTRA = (("Fe", "Fe/nk/Johnson.yml", "Johnson and Christy 1974"),
         ("Ni", "Ni/nk/Johnson.yml", "Johnson and Christy 1974"),
         ("Pt", "Pt/nk/Rakic-BB.yml", "Rakic et al. 1998 (Brendel-Bormann fit)"),
         ("Ti", "Ti/nk/Johnson.yml", "Johnson and Christy 1974"))


def read_cie(path: Path) -> np.ndarray:
    """(95, 3) float32: x, y, z at 360, 365, ..., 830 nm."""
    rows = {}
    for line in path.read_text().splitlines():
        parts = line.strip().split(",")
        try:
            nm = float(parts[0])
        except ValueError:
            continue  # a header
        rows[nm] = [float(p) for p in parts[1:4]]
    grid = CIE_MIN + 5.0 * np.arange(CIE_SAMPLES)
    missing = [nm for nm in grid if nm not in rows]
    if missing:
        raise SystemExit(f"error: {path}: no CIE rows for {missing[:3]}... (need 360-830 nm)")
    return np.array([rows[nm] for nm in grid], np.float32)


def cmf(table: np.ndarray, w: float) -> np.ndarray:
    """Mitsuba's cie1931_xyz: linear between the 5 nm rows, 0 outside [360, 830]."""
    if w < CIE_MIN or w > CIE_MAX:
        return np.zeros(3)
    t = (w - CIE_MIN) * ((CIE_SAMPLES - 1) / (CIE_MAX - CIE_MIN))
    i0 = min(max(int(t), 0), CIE_SAMPLES - 2)
    w1 = t - i0
    return (1.0 - w1) * table[i0].astype(np.float64) + w1 * table[i0 + 1].astype(np.float64)


def spectrum_to_rgb(wavelengths, values, table) -> np.ndarray:
    """Mitsuba 3's spectrum_list_to_srgb(bounded=false, d65=false), as float32."""
    wavelengths = np.asarray(wavelengths, np.float64)
    values = np.asarray(values, np.float64)
    xyz = np.zeros(3)
    for i in range(STEPS):
        w = CIE_MIN + (i / (STEPS - 1)) * (CIE_MAX - CIE_MIN)
        if w < wavelengths[0] or w > wavelengths[-1]:
            continue
        # the last interval whose left end is <= w (clamped to a valid interval)
        index = int(np.clip(np.searchsorted(wavelengths, w, side="right") - 1, 0, len(wavelengths) - 2))
        w0, w1 = wavelengths[index], wavelengths[index + 1]
        v0, v1 = values[index], values[index + 1]
        v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1)
        xyz += cmf(table, w) * v
    xyz *= (CIE_MAX - CIE_MIN) * Y_NORMALIZATION / STEPS
    rgb = np.maximum(XYZ_TO_SRGB @ xyz, 0.0)
    return rgb.astype(np.float32)


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
    parser.add_argument("--cie", type=Path, required=True, help="CIE_xyz_1931_2deg.csv (360-830 nm)")
    args = parser.parse_args()
    table = read_cie(args.cie)
    rows = []
    for eta_file in sorted(args.mitsuba_ior.glob("*.eta.spd")):
        name = eta_file.name[:-len(".eta.spd")]
        k_file = eta_file.with_name(f"{name}.k.spd")
        eta_w, eta_v = read_spd(eta_file)
        k_w, k_v = read_spd(k_file)
        source = "Mitsuba 3 preset (Luxpop: Palik; CXRO/LLNL)"
        if eta_w[0] > CIE_MIN or eta_w[-1] < CIE_MAX or k_w[0] > CIE_MIN or k_w[-1] < CIE_MAX:
            source += f"; spectrum covers {min(eta_w[0], k_w[0]):.0f}-{max(eta_w[-1], k_w[-1]):.0f} nm only"
        rows.append((name, spectrum_to_rgb(eta_w, eta_v, table), spectrum_to_rgb(k_w, k_v, table), source))
    for name, file, citation in EXTRA:
        nm, n, k = read_tabulated_nk(args.refractiveindex / file)
        rows.append((name, spectrum_to_rgb(nm, n, table), spectrum_to_rgb(nm, k, table),
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

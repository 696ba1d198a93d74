"""Named measured metals: the RGB complex index of refraction (eta, k) of each `metal = "..."` a
conductor may name, read from data/metals.csv (written by scripts/make_metal_table.py from
measured spectra, converted to RGB as Mitsuba 3's RGB variants convert its presets).

Plain Python, no Taichi: the scene schema reads the names from here.
"""
import csv
from functools import lru_cache
from pathlib import Path

TABLE_FILE = Path(__file__).resolve().parent / "data" / "metals.csv"


@lru_cache(maxsize=1)
def _table() -> dict:
    try:
        lines = TABLE_FILE.read_text(encoding="utf-8").splitlines()
    except OSError as error:
        raise RuntimeError(f"{TABLE_FILE}: cannot read the metal table ({error}); "
                           "run scripts/make_metal_table.py") from None
    rows = csv.DictReader(line for line in lines if not line.startswith("#"))
    return {row["name"]: ((float(row["eta_r"]), float(row["eta_g"]), float(row["eta_b"])),
                          (float(row["k_r"]), float(row["k_g"]), float(row["k_b"])), row["source"])
            for row in rows}


def metal_names() -> tuple[str, ...]:
    return tuple(_table())


def metal_ior(name: str) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(eta, k), RGB, of a named metal (KeyError for an unknown name)."""
    eta, k, _ = _table()[name]
    return eta, k


def metal_source(name: str) -> str:
    return _table()[name][2]

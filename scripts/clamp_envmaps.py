"""Clamp the negative values of the shipped environment maps to 0, in the files themselves.

    .venv/bin/python scripts/clamp_envmaps.py [MAP.exr ...]     (default: every assets/envmaps/*.exr)

The Poly Haven maps in assets/envmaps came with the ringing of their lossy (DWAB) compression: a
few values below zero, which the reader clamps with a warning on every load. This writes each map
that has any with exactly the values the reader used (np.maximum(value, 0.0) of the same half
floats: negative values and -0 become +0), so renders do not change by a bit and loading warns of nothing. Everything else stays:
channels, their half-float type, size and header; only the compression changes where it has to,
from a lossy one (which would quantise every pixel again, and ring again) to PIZ, lossless and
read by every OpenEXR version. The new file is checked against the reader's values before it
replaces the old one. Maps without negative values (and Radiance .hdr files, which cannot hold
any) are left alone, so running it again changes nothing.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

ENVMAPS = ROOT / "assets" / "envmaps"
LOSSLESS = ("NO_COMPRESSION", "RLE_COMPRESSION", "ZIPS_COMPRESSION", "ZIP_COMPRESSION", "PIZ_COMPRESSION")
REPLACEMENT = "PIZ_COMPRESSION"  # the smallest lossless one for these photographs (ZIP: about 8% larger)


def clamp_map(path: Path) -> str:
    """Clamp `path`'s negative values in place (atomically); what was done, in one line."""
    import OpenEXR

    from renderer.output.atomic_write import atomic_output
    from renderer.output.image_io import read_exr

    with OpenEXR.File(os.fspath(path), separate_channels=True) as exr:
        header = dict(exr.header())
        channels = {name: np.array(channel.pixels) for name, channel in exr.channels().items()}
    negative = {name: int(np.count_nonzero(pixels < 0)) for name, pixels in channels.items()}
    if not any(negative.values()):
        return f"{path}: no negative values, unchanged"
    expected = np.maximum(read_exr(path), 0.0)  # what the reader renders with (read_environment)
    compression = header["compression"]
    if compression.name not in LOSSLESS:
        header["compression"] = getattr(OpenEXR, REPLACEMENT)
    # +0 for every value with its sign bit set: the reader's float32 np.maximum(value, 0.0) turns -0
    # into +0 as well (numpy's half-float maximum would keep -0).
    clamped = {name: np.where(np.signbit(pixels), np.zeros((), pixels.dtype), pixels)
               for name, pixels in channels.items()}
    before = path.stat().st_size
    with atomic_output(path) as temporary:
        with OpenEXR.File(header, dict(clamped)) as exr:
            exr.write(os.fspath(temporary))
        _check_rewrite(temporary, header, clamped, expected)
    changed = (f"; {compression.name} -> {header['compression'].name} (lossless)"
               if header["compression"] != compression else "")
    return (f"{path}: clamped {sum(negative.values())} negative values to 0{changed}, "
            f"{before} -> {path.stat().st_size} bytes")


def _check_rewrite(path: Path, header: dict, clamped: dict[str, np.ndarray], expected: np.ndarray) -> None:
    """The written file has the header, channel types and values intended, and reads as `expected`
    bit for bit; else raise (the original file stays)."""
    import OpenEXR

    from renderer.output.image_io import read_exr

    with OpenEXR.File(os.fspath(path), separate_channels=True) as exr:
        written = dict(exr.header())
        channels = {name: np.array(channel.pixels) for name, channel in exr.channels().items()}
    problems = [key for key in set(header) | set(written) if key != "channels" and
                not _same(header.get(key), written.get(key))]
    if sorted(channels) != sorted(clamped):
        problems.append("channel names")
    for name, pixels in clamped.items():
        if name in channels and (channels[name].dtype != pixels.dtype
                                 or not np.array_equal(channels[name].view(np.uint8), pixels.view(np.uint8))):
            problems.append(f"channel {name}")
    if not np.array_equal(read_exr(path).view(np.uint32), expected.astype(np.float32).view(np.uint32)):
        problems.append("the values read back")
    if problems:
        raise RuntimeError(f"{path}: the rewritten map differs in {', '.join(sorted(problems))}")


def _same(a, b) -> bool:
    if isinstance(a, tuple) or isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(a, b)
    return a == b


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("maps", nargs="*", type=Path, help="EXR maps (default: every assets/envmaps/*.exr)")
    args = parser.parse_args(argv)
    for path in args.maps or sorted(ENVMAPS.glob("*.exr")):
        print(clamp_map(path))
    return 0


if __name__ == "__main__":
    sys.exit(main())

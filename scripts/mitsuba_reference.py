"""Render reference images with Mitsuba 3, an independent renderer: its Cornell box, or (--scene
glass) the smooth glass of tests/data/glass_reference.toml under an environment map.

    .venv/bin/python scripts/mitsuba_reference.py [--scene cornell|glass] [--size 64] [--passes 64]
                                                  [--spp 1024] [--threads N]

The glass files (tests/data/glass_mitsuba_mean.exr, glass_mitsuba_var.exr) were made by

    python scripts/mitsuba_reference.py --scene glass --size 48 --passes 32 --spp 1024 --threads 2

Mitsuba's `mi.cornell_box()` (the scene assets/scenes/cornell_box.toml reproduces value for value)
is rendered with its `path` integrator, max_depth 8 as in cornell_box(), at --size x --size
pixels, with a `box` reconstruction filter (each pixel is the plain average over its own area, as
Lantern's film computes it; Mitsuba's default is a Gaussian, which blurs across pixels). It takes
--passes independent renders (seeds 0, 1, ...) of --spp samples per pixel each and writes

    tests/data/cornell_mitsuba_mean.exr   per-pixel mean of the pass means (linear RGB, float32)
    tests/data/cornell_mitsuba_var.exr    per-pixel variance of that mean: the unbiased sample
                                          variance of the pass means over the passes, / passes

Mitsuba's `path` samples the light as well as the BSDF, and each pass averages --spp samples, so
the pass means are close to normal and their sample variance is a sound estimate. The EXR headers
record the Mitsuba version, variant, passes and spp. tests/render/test_mitsuba_reference.py
compares Lantern with these files; it does not need Mitsuba.

The committed files were produced by

    .venv/bin/python scripts/mitsuba_reference.py --size 64 --passes 64 --spp 1024 --threads 2

with Mitsuba 3.9.1, variant llvm_ad_rgb (DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so,
Debian's libllvm19), on a 2-core machine that was busy with other work: 65,536 spp in total, in
215 s (1.25 M samples/s; ~160 s when idle). Their standard error is 1/8 of that of a 1,024-spp
render with the same noise per sample (sqrt(1024 / 65536)); measured against Lantern's `mis` at
1,024 spp, the reference's variance of the mean is 1/61 of Lantern's (median over pixels).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a plain script from anywhere
    sys.path.insert(0, str(ROOT))

from renderer.bench import mitsuba_side  # noqa: E402  (imports mitsuba lazily)

DATA = ROOT / "tests" / "data"
# scene name -> (file name stem, what the headers say, how to load it at a size)
SCENES = {
    "cornell": ("cornell_mitsuba", "Mitsuba 3 mi.cornell_box(), path integrator, max_depth 8, box filter",
                lambda size: mitsuba_side.load_cornell_box(size, size)),
    "glass": ("glass_mitsuba", "Mitsuba 3, tests/data/glass_reference.toml value for value, path integrator, "
              "max_depth 16, box filter", None),
}


def _load(name: str, size: int):
    if name == "glass":
        import mitsuba as mi

        return mi.load_dict(mitsuba_side.glass_scene_dict(size, size))
    return SCENES[name][2](size)


def render_reference(size: int, passes: int, spp: int, threads: int | None, seed: int = 0, scene_name="cornell"):
    """(mean, variance of the mean), float64 (size, size, 3), and the seconds spent rendering."""
    if passes < 2:
        raise ValueError("at least 2 passes are needed to estimate the variance")
    mitsuba_side.set_threads(threads)
    scene = _load(scene_name, size)
    # Welford over the pass means, in float64.
    mean = np.zeros((size, size, 3))
    m2 = np.zeros((size, size, 3))
    start = time.perf_counter()
    for k in range(passes):
        image = mitsuba_side.render_scene(scene, spp, seed + k).astype(np.float64)
        delta = image - mean
        mean += delta / (k + 1)
        m2 += delta * (image - mean)
        print(f"pass {k + 1}/{passes}: {time.perf_counter() - start:.1f} s", end="\r", flush=True)
    seconds = time.perf_counter() - start
    print()
    variance_of_mean = m2 / (passes - 1) / passes
    return mean, variance_of_mean, seconds


def write_exr(path: Path, rgb: np.ndarray, attributes: dict) -> None:
    """Float32, ZIP-compressed EXR with string attributes in its header (row 0 = top)."""
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    header.update({key: str(value) for key, value in attributes.items()})
    path.parent.mkdir(parents=True, exist_ok=True)
    with OpenEXR.File(header, {"RGB": np.ascontiguousarray(rgb, dtype=np.float32)}) as exr:
        exr.write(str(path))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=64, help="image width and height in pixels")
    parser.add_argument("--passes", type=int, default=64, help="independent renders (seeds 0..passes-1)")
    parser.add_argument("--spp", type=int, default=1024, help="samples per pixel of each pass")
    parser.add_argument("--threads", type=int, default=None, help="Mitsuba worker threads (default: all)")
    parser.add_argument("--out-dir", type=Path, default=DATA)
    parser.add_argument("--scene", choices=sorted(SCENES), default="cornell",
                        help="cornell: mi.cornell_box(); glass: tests/data/glass_reference.toml")
    args = parser.parse_args(argv)

    info = mitsuba_side.availability()
    if not info["available"]:
        print(f"error: {info['note']}", file=sys.stderr)
        return 1
    print(f"Mitsuba {info['version']}, variant {info['variant']}" + (f" ({info['note']})" if info["note"] else ""))

    mean, variance_of_mean, seconds = render_reference(args.size, args.passes, args.spp, args.threads,
                                                       scene_name=args.scene)
    stem, description, _ = SCENES[args.scene]
    attributes = {
        "lanternReference": description,
        "mitsubaVersion": info["version"], "mitsubaVariant": info["variant"],
        "passes": args.passes, "sppPerPass": args.spp, "sppTotal": args.passes * args.spp,
    }
    mean_file, var_file = args.out_dir / f"{stem}_mean.exr", args.out_dir / f"{stem}_var.exr"
    write_exr(mean_file, mean, {**attributes, "content": "per-pixel mean"})
    write_exr(var_file, variance_of_mean, {**attributes, "content": "per-pixel variance of the mean"})
    total = args.passes * args.spp
    print(f"{total} spp ({args.passes} x {args.spp}) at {args.size}x{args.size} in {seconds:.1f} s "
          f"({args.size * args.size * total / seconds / 1e6:.2f} M samples/s)")
    print(f"image mean {mean.mean(axis=(0, 1))}, median relative standard error "
          f"{np.median(np.sqrt(variance_of_mean) / np.maximum(mean, 1e-6)):.2e}")
    print(f"wrote {mean_file} and {var_file}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Fingerprints of a fixed set of renders, to prove that a refactoring changes no image.

    python scripts/image_fingerprints.py --write before.json     # on the tree before the change
    python scripts/image_fingerprints.py --check before.json     # after it: every image bit-identical?

Each case is a (scene, integrator, seed) rendered small (64x36, 4 spp) on the CPU with ONE thread:
SPPM adds photon contributions with float atomics, whose order (and so the last bits) depends on
thread scheduling; with one thread every image is reproducible bit for bit. The fingerprint is the
SHA-256 of the film's float32 mean image; --check also prints the largest difference of any image
that changed (it keeps the images in a .npz beside the JSON for that).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

SIZE = (64, 36)
SPP = 4
# (scene name, file or None for the catalog, integrator, seed)
CASES = [
    ("showcase", "mis", 1), ("hard_cases", "path", 2), ("mirror_field", "nee", 3), ("foggy", "mis", 4),
    ("prism", "mis", 5), ("cornell_box", "mis", 6), ("cornell_box", "nee", 6), ("cornell_box", "path", 6),
    ("cornell_box", "sppm", 6), ("bunnies", "mis", 7), ("textured", "mis", 8), ("many_lights", "mis", 9),
    ("weekend", "mis", 10), ("goblet", "sppm", 11), ("pool", "mis", 12), ("stress", "albedo", 13),
    ("studio", "mis", 14), ("showcase", "normals", 15), ("cornell_box", "bvh", 16), ("showcase", "steps", 17),
    ("tests/data/glass_reference.toml", "mis", 18), ("tests/data/glass_reference.toml", "sppm", 19),
    ("tests/data/cutout.gltf", "mis", 20), ("tests/data/colored_quads.gltf", "mis", 21),
    ("tests/data/simple_instancing.gltf", "mis", 22), ("tests/data/textured_quad.glb", "mis", 23),
    ("tests/data/materials.obj", "mis", 24), ("tests/data/pyramid.ply", "path", 25),
]


def render_all(only: str | None = None) -> dict[str, np.ndarray]:
    from renderer.runtime.arch import init_taichi

    init_taichi("cpu", cpu_threads=1)
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any, resolve_scene

    images = {}
    for name, integrator, seed in CASES:
        if only and only not in f"{name}:{integrator}:{seed}":
            continue
        path = ROOT / name if "/" in name else resolve_scene(name)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene = load_any(path)
            r = Renderer(scene, SIZE)
            r.render(CameraFrame.from_spec(scene.camera), SPP, integrator=integrator, seed=seed)
        images[f"{name}:{integrator}:{seed}"] = np.ascontiguousarray(r.film.mean_image(), np.float32)
        print(f"{name:40s} {integrator:8s} done", flush=True)
    return images


def fingerprint(image: np.ndarray) -> str:
    return hashlib.sha256(image.tobytes()).hexdigest()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--write", type=Path, help="write the fingerprints (and images) of this tree")
    group.add_argument("--check", type=Path, help="compare this tree's renders with written fingerprints")
    parser.add_argument("--only", metavar="TEXT", help="only the cases whose scene:integrator:seed contains TEXT")
    args = parser.parse_args(argv)
    images = render_all(args.only)
    if args.write:
        args.write.write_text(json.dumps({k: fingerprint(v) for k, v in images.items()}, indent=1))
        np.savez_compressed(args.write.with_suffix(".npz"), **{k.replace("/", "|"): v for k, v in images.items()})
        print(f"wrote {len(images)} fingerprints to {args.write}")
        return 0
    expected = json.loads(args.check.read_text())
    stored = np.load(args.check.with_suffix(".npz"))
    changed = 0
    for key, image in images.items():
        if key not in expected:
            print(f"NEW       {key}")
            continue
        if fingerprint(image) == expected[key]:
            continue
        changed += 1
        before = stored[key.replace("/", "|")]
        print(f"CHANGED   {key}: largest difference {np.abs(image - before).max():.3e}, "
              f"mean {np.abs(image - before).mean():.3e}")
    missing = sorted(key for key in set(expected) - set(images) if not args.only or args.only in key)
    for key in missing:
        print(f"MISSING   {key}")
    print(f"{len(images) - changed} of {len(images)} images bit-identical")
    return 1 if changed or missing else 0


if __name__ == "__main__":
    sys.exit(main())

"""Mitsuba 3 rendering its Cornell box as a process of its own, the way a user runs it: the
counterpart of `python app.py render cornell_box ...` in `bench integrators`' whole-process
comparison (renderer/bench/whole_process.py).

    python -m renderer.bench.mitsuba_process --size 256 --spp 256 --max-depth 8 --seed 0 --threads 2 --out img.npy

Imports Mitsuba (and nothing of Lantern's that starts Taichi), loads `mi.cornell_box()` with a box
filter (renderer.bench.mitsuba_side.cornell_box_dict), renders once and saves the linear RGB image
(float32, row 0 = top) as .npy. It prints "(N spp in T s)" for the render call, as Lantern's
`render` does, so the comparison can read the render apart from start-up (imports, scene loading,
JIT kernels from the cache) and the rest. Exit status 3, with a one-line message, where Mitsuba is
unusable.
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m renderer.bench.mitsuba_process")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--spp", type=int, default=256)
    parser.add_argument("--max-depth", type=int, default=8)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=None)
    parser.add_argument("--out", required=True)
    args = parser.parse_args(argv)

    from renderer.bench import mitsuba_side as ms

    try:
        ms.set_threads(args.threads)
        scene = ms.load_cornell_box(args.size, args.size, args.max_depth)
    except ms.MitsubaUnavailable as error:
        print(f"mitsuba_process: {error}", file=sys.stderr)
        return 3
    start = time.perf_counter()
    image = ms.render_scene(scene, args.spp, seed=args.seed)  # np.array() waits for the JIT's work
    seconds = time.perf_counter() - start
    np.save(args.out, image)
    print(f"{args.out}  ({args.spp} spp in {seconds:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

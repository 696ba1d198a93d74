"""The same SPPM render on each given number of CPU threads, one Taichi runtime after another in
this process (the thread count is fixed per runtime, and the suite's runtime is the test's):
`python -m tests.render.sppm_threads_child OUT_PREFIX THREADS [THREADS ...]`. Per count, prints a
JSON line with the thread count Taichi used and the photons emitted, and writes the image and the
per-pixel photon state to OUT_PREFIX<THREADS>.npz."""
import json
import sys

import numpy as np


def render_on(threads: int, out: str) -> dict:
    import taichi as ti

    from renderer.runtime.arch import init_taichi
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any, resolve_scene

    init_taichi("cpu", cpu_threads=threads)  # the suite's optimisation level: the offline cache serves it
    try:
        scene = load_any(resolve_scene("cornell_box"))
        renderer = Renderer(scene, (16, 16))
        renderer.render(CameraFrame.from_spec(scene.camera), 6, "sppm", seed=11)
        state = renderer.shared("sppm_state", None)
        np.savez(out, image=renderer.image(), radius=state.radii(16, 16), n=state.photon_counts(16, 16),
                 tau=state.tau_image(16, 16))
        return {"threads": ti.lang.impl.current_cfg().cpu_max_num_threads, "photons": state.photons_emitted}
    finally:
        ti.reset()


def main(argv: list[str]) -> int:
    prefix, counts = argv[0], [int(v) for v in argv[1:]]
    for threads in counts:
        print(json.dumps(render_on(threads, f"{prefix}{threads}.npz")), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

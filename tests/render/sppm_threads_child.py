"""One SPPM render in a process of its own, on a given number of CPU threads (the runtime is per
process): `python -m tests.render.sppm_threads_child THREADS OUT.npz`. Prints a JSON line with the
thread count Taichi used and the photons emitted; writes the image and the per-pixel photon state."""
import json
import sys

import numpy as np


def main(argv: list[str]) -> int:
    import taichi as ti

    from renderer.arch import init_taichi
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any, resolve_scene

    threads, out = int(argv[0]), argv[1]
    init_taichi("cpu", cpu_threads=threads)  # the suite's optimisation level: the offline cache serves it
    scene = load_any(resolve_scene("cornell_box"))
    renderer = Renderer(scene, (16, 16))
    renderer.render(CameraFrame.from_spec(scene.camera), 6, "sppm", seed=11)
    state = renderer.shared("sppm_state", None)
    np.savez(out, image=renderer.image(), radius=state.radii(16, 16), n=state.photon_counts(16, 16),
             tau=state.tau_image(16, 16))
    print(json.dumps({"threads": ti.lang.impl.current_cfg().cpu_max_num_threads,
                      "photons": state.photons_emitted}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

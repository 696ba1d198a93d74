"""CPU seconds of a cold first render (compile + one sample at 64x36) with and without the
cheaper Taichi front end (renderer/runtime/taichi_frontend.py), runs interleaved in fresh processes.

    python scripts/frontend_cost.py [scene] [integrator] [runs]
"""
import statistics
import subprocess
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def cold_first_render(scene_name: str, integrator: str, cheaper: bool) -> float:
    """In this process (a fresh one): CPU seconds of the first render, offline cache off."""
    sys.path.insert(0, str(ROOT))
    import taichi as ti

    from renderer.runtime.arch import init_taichi
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any, resolve_scene
    from viewer.session import camera_from_spec
    from viewer.window import camera_frame

    init_taichi("cpu", offline_cache=False, cheaper_frontend=cheaper)
    warnings.simplefilter("ignore")
    scene = load_any(resolve_scene(scene_name))
    renderer = Renderer(scene, max_size=(64, 36))
    t0 = time.process_time()
    renderer.render(camera_frame(camera_from_spec(scene.camera)), 1, integrator)
    ti.sync()
    return time.process_time() - t0


def one_run(scene: str, integrator: str, cheaper: bool) -> float:
    out = subprocess.run([sys.executable, __file__, "--child", scene, integrator, str(int(cheaper))],
                         capture_output=True, text=True, check=True).stdout
    return float(next(line for line in out.splitlines() if line.startswith("CPU")).split()[1])


def main(argv: list[str]) -> int:
    if argv[:1] == ["--child"]:
        print("CPU", cold_first_render(argv[1], argv[2], argv[3] == "1"))
        return 0
    scene = argv[0] if argv else "studio"
    integrator = argv[1] if len(argv) > 1 else "mis"
    runs = int(argv[2]) if len(argv) > 2 else 4
    seconds = {False: [], True: []}
    for _ in range(runs):
        for cheaper in (False, True):
            seconds[cheaper].append(one_run(scene, integrator, cheaper))
    for cheaper, values in seconds.items():
        label = "cheaper front end" if cheaper else "Taichi's own     "
        print(f"{label}: median {statistics.median(values):.2f} s CPU  ({', '.join(f'{v:.2f}' for v in values)})")
    ratio = statistics.median(seconds[True]) / statistics.median(seconds[False])
    print(f"{scene} / {integrator}: cold first render at {ratio:.2f}x the CPU time")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

"""CPU seconds of a cold first render (compile + one sample at 64x36) with and without the
cheaper Taichi front end (renderer/taichi_frontend.py), runs interleaved in fresh processes.

    python scripts/frontend_cost.py [scene] [integrator] [runs]
"""
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

ONE_RUN = """
import sys, time, warnings
sys.path.insert(0, {root!r})
import taichi as ti
from renderer import taichi_frontend
if {patched}:
    taichi_frontend.install()
ti.init(arch=ti.cpu, offline_cache=False, advanced_optimization=False, log_level=ti.WARN)
warnings.simplefilter("ignore")
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any, resolve_scene
from viewer.session import camera_from_spec
from viewer.window import camera_frame
scene = load_any(resolve_scene({scene!r}))
renderer = Renderer(scene, max_size=(64, 36))
t0 = time.process_time()
renderer.render(camera_frame(camera_from_spec(scene.camera)), 1, {integrator!r})
ti.sync()
print("CPU", time.process_time() - t0)
"""


def one_run(scene: str, integrator: str, patched: bool) -> float:
    code = ONE_RUN.format(root=str(ROOT), patched=patched, scene=scene, integrator=integrator)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    return float(next(line for line in out.splitlines() if line.startswith("CPU")).split()[1])


def main(argv: list[str]) -> int:
    scene = argv[0] if argv else "studio"
    integrator = argv[1] if len(argv) > 1 else "mis"
    runs = int(argv[2]) if len(argv) > 2 else 4
    seconds = {False: [], True: []}
    for _ in range(runs):
        for patched in (False, True):
            seconds[patched].append(one_run(scene, integrator, patched))
    for patched, values in seconds.items():
        label = "cheaper front end" if patched else "Taichi's own     "
        print(f"{label}: median {statistics.median(values):.2f} s CPU  ({', '.join(f'{v:.2f}' for v in values)})")
    ratio = statistics.median(seconds[True]) / statistics.median(seconds[False])
    print(f"{scene} / {integrator}: cold first render at {ratio:.2f}x the CPU time")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

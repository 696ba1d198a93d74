"""What a viewer edit costs, measured in one process: the Cornell box at 256x256 under `mis`, a
colour edit (20 of them; median), a kind edit and the render that compiles its kernel, and an
emission edit (the light selection reweighed in place, nothing compiled).

    python scripts/edit_latency.py
"""
from __future__ import annotations

import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


def seconds(action) -> float:
    import taichi as ti

    start = time.perf_counter()
    action()
    ti.sync()
    return time.perf_counter() - start


def main() -> int:
    from renderer.camera import CameraFrame
    from renderer.editing import canonical, material_named, with_material
    from renderer.renderer import Renderer
    from renderer.runtime.arch import init_taichi
    from renderer.scene import load_scene

    init_taichi("cpu")
    scene = load_scene(ROOT / "assets" / "scenes" / "cornell_box.toml")
    renderer = Renderer(scene)
    camera = CameraFrame.from_spec(scene.camera)

    def one_sample():
        renderer.render(camera, 1, "mis")

    seconds(one_sample)  # compiles the scene's own kernel
    box = material_named(scene, "tall_box")
    colour = [seconds(lambda i=i: renderer.edit_materials(
        with_material(renderer.scene, replace(box, base_color=(0.1 + 0.04 * i, 0.5, 0.5))))) for i in range(20)]
    after_colour = seconds(one_sample)
    gold = with_material(renderer.scene, canonical(replace(box, kind="conductor", metal="Au", roughness=0.3)))
    kind = seconds(lambda: renderer.edit_materials(gold))
    first_gold, next_gold = seconds(one_sample), seconds(one_sample)
    light = material_named(renderer.scene, "light")
    brighter = with_material(renderer.scene, replace(light, emission=tuple(2 * c for c in light.emission)))
    emission = seconds(lambda: (renderer.edit_materials(brighter), one_sample()))
    print(f"colour edit: median {1000 * statistics.median(colour):.2f} ms over 20; the next 1 spp {1000 * after_colour:.0f} ms")
    print(f"kind edit (diffuse -> gold conductor): {1000 * kind:.1f} ms; the first 1 spp after it {first_gold:.2f} s "
          f"(compiles), the next {1000 * next_gold:.0f} ms")
    print(f"emission edit and 1 spp (lights reweighed in place): {emission * 1e3:.0f} ms")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The wide BVH on a back-end of its own, in a process of its own (the suite's runtime is on the
CPU): `python -m tests.geometry.wide_bvh_vulkan_child hits OUT` or
`... render OUT ARCH TRAVERSAL SEED` (TRAVERSAL: a MeshOptions traversal, "+packets" for the packet
leaves). Writes its arrays to OUT (.npz)."""
import sys

import numpy as np


def hits(out: str) -> None:
    """Closest hits and shadow tests of the stack, wide4 and wide8 traversals on Vulkan, the wide
    ones with the scalar and the packet leaves."""
    from renderer.runtime.arch import init_taichi

    init_taichi("vulkan")
    from renderer.bench.bvh_measure import traversal_and_leaves
    from tests.geometry.mesh_helpers import RayShooter, geometry_from
    from tests.geometry.test_traversal import mixed_scene, random_rays

    rng = np.random.default_rng(1)
    data, (o, d) = mixed_scene(rng), random_rays(rng, 4000)
    arrays = {}
    for traversal in ("stack", "wide4", "wide4+packets", "wide8", "wide8+packets"):
        base, leaves = traversal_and_leaves(traversal)
        shooter = RayShooter(geometry_from(data, traversal=base, leaves=leaves))
        arrays[traversal + "_t"], arrays[traversal + "_prim"] = shooter.closest(o, d)
        arrays[traversal + "_shadow"] = shooter.occluded(o, d, 1.5)
    np.savez(out, **arrays)


def render(out: str, arch: str, traversal: str, seed: int) -> None:
    """The Cornell box at 24x24, 32 spp of mis, on `arch` with `traversal`: mean and variance."""
    from renderer.runtime.arch import init_taichi

    init_taichi(arch)
    from renderer.bench.bvh_measure import traversal_and_leaves
    from renderer.camera import CameraFrame
    from renderer.renderer import MeshOptions, Renderer
    from renderer.scene.catalog import load_any

    scene = load_any("assets/scenes/cornell_box.toml")
    base, leaves = traversal_and_leaves(traversal)
    r = Renderer(scene, (24, 24), mesh_options=MeshOptions(traversal=base, leaves=leaves))
    r.render(CameraFrame.from_spec(scene.camera), 32, integrator="mis", seed=seed)
    np.savez(out, mean=r.image(), var=r.film.variance_of_mean_image())


def main(argv: list[str]) -> int:
    if argv[0] == "hits":
        hits(argv[1])
    else:
        render(argv[1], argv[2], argv[3], int(argv[4]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

"""Mitsuba 3 as an independent renderer: its Cornell box and a glass scene, rendered for reference
images and timing.

Mitsuba is optional (`pip install -e .[reference]`). Nothing here imports it at module import time;
the first call that needs it does, and fails with `MitsubaUnavailable` and a message saying what
to install when it cannot.

Its LLVM variants (`llvm_ad_rgb`, `llvm_rgb`) JIT-compile through a system libLLVM found via the
environment variable DRJIT_LIBLLVM_PATH; on Debian 12 that is the `libllvm19` package, at
/usr/lib/x86_64-linux-gnu/libLLVM-19.so. The variable is set before `import mitsuba` when it is
unset and that file exists. Without it (the variable unset and no such file) the LLVM variants are
not tried: Dr.Jit would look for any libLLVM on the system, and one too old for it (Debian 12's
LLVM 14 and 15) aborts the whole process at the first render, past any exception handler. The
`scalar_rgb` variant (no JIT, much slower) is used then, and `availability()` says so in its note.

The scene is `mi.cornell_box()` (the one assets/scenes/cornell_box.toml reproduces), with two
changes made by `cornell_box_dict`: the film size, and a `box` reconstruction filter instead of
Mitsuba's default Gaussian, so that each pixel is the plain average of the radiance over its own
area, as Lantern's film computes it.
"""
from __future__ import annotations

import functools
import os
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

DEFAULT_LIBLLVM = "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"
PREFERRED_VARIANTS = ("llvm_ad_rgb", "llvm_rgb")
FALLBACK_VARIANT = "scalar_rgb"
INSTALL_HINT = ("install it with `pip install mitsuba` (or `pip install -e .[reference]`); its LLVM "
                "variants also need Debian's libllvm19 (`apt-get install libllvm19`)")


class MitsubaUnavailable(RuntimeError):
    """Mitsuba 3 cannot be imported, or has no RGB variant this module can use."""


class MitsubaRender(NamedTuple):
    image: np.ndarray  # linear RGB, float32 (height, width, 3), row 0 = top
    seconds: float  # wall clock of the timed render (JIT compilation excluded when warmed up)
    samples_per_second: float  # width * height * spp / seconds (camera samples, not rays)


@functools.cache  # a failure is not cached: the next call tries again
def _import_mitsuba():
    """Import mitsuba once, set its variant, and return (mi, variant, note)."""
    if "DRJIT_LIBLLVM_PATH" not in os.environ and Path(DEFAULT_LIBLLVM).is_file():
        os.environ["DRJIT_LIBLLVM_PATH"] = DEFAULT_LIBLLVM
    try:
        import mitsuba as mi
    except ImportError as error:
        raise MitsubaUnavailable(f"Mitsuba 3 is not installed ({error}); {INSTALL_HINT}") from None
    available = set(mi.variants())
    note = ""
    llvm_variants = PREFERRED_VARIANTS
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        llvm_variants = ()
        note = f"no libLLVM named (DRJIT_LIBLLVM_PATH unset, no {DEFAULT_LIBLLVM}: `apt-get install libllvm19`)"
    for variant in llvm_variants:
        if variant not in available:
            continue
        try:
            mi.set_variant(variant)
            break
        except Exception as error:  # the LLVM backend failed to start (libLLVM missing or wrong)
            note = f"{variant} unavailable ({str(error).strip().splitlines()[0]})"
    else:
        if FALLBACK_VARIANT not in available:
            raise MitsubaUnavailable(f"Mitsuba {mi.__version__} has none of the variants "
                                     f"{', '.join(PREFERRED_VARIANTS + (FALLBACK_VARIANT,))}")
        mi.set_variant(FALLBACK_VARIANT)
        variant = FALLBACK_VARIANT
        note = (note or "no LLVM variant") + (f"; using {FALLBACK_VARIANT} (no JIT, much slower); set "
                                              f"DRJIT_LIBLLVM_PATH to a libLLVM (e.g. {DEFAULT_LIBLLVM})")
    return mi, variant, note


def availability() -> dict:
    """{'available': bool, 'version', 'variant', 'libllvm', 'note'}: never raises."""
    try:
        mi, variant, note = _import_mitsuba()
    except MitsubaUnavailable as error:
        return {"available": False, "version": None, "variant": None,
                "libllvm": os.environ.get("DRJIT_LIBLLVM_PATH"), "note": str(error)}
    return {"available": True, "version": mi.__version__, "variant": variant,
            "libllvm": os.environ.get("DRJIT_LIBLLVM_PATH") if variant.startswith("llvm") else None,
            "note": note}


def is_available() -> bool:
    return availability()["available"]


def set_threads(threads: int | None) -> None:
    """Limit Mitsuba's worker threads (None leaves its default: all hardware threads)."""
    if threads is None:
        return
    _import_mitsuba()
    import drjit as dr

    # Dr.Jit's thread pool runs the LLVM kernels and Mitsuba's scalar render blocks alike.
    dr.set_thread_count(int(threads))


def cornell_box_dict(width: int = 256, height: int = 256, max_depth: int = 8, rfilter: str = "box",
                     sampler: str | None = None) -> dict:
    """`mi.cornell_box()` with the film resized, the reconstruction filter replaced and (if given)
    another sampler (Mitsuba's default is `independent`)."""
    mi, _, _ = _import_mitsuba()
    scene = mi.cornell_box()
    film = scene["sensor"]["film"]
    film["width"], film["height"] = int(width), int(height)
    film["rfilter"] = {"type": rfilter}
    scene["integrator"] = {"type": "path", "max_depth": int(max_depth)}
    if sampler is not None:
        scene["sensor"]["sampler"] = {"type": sampler, "sample_count": scene["sensor"]["sampler"]["sample_count"]}
    return scene


def load_cornell_box(width: int = 256, height: int = 256, max_depth: int = 8, rfilter: str = "box",
                     sampler: str | None = None):
    mi, _, _ = _import_mitsuba()
    return mi.load_dict(cornell_box_dict(width, height, max_depth, rfilter, sampler))


GLASS_SCENE = Path(__file__).resolve().parents[2] / "tests" / "data" / "glass_reference.toml"


def glass_scene_dict(width: int = 48, height: int = 48, max_depth: int = 16) -> dict:
    """tests/data/glass_reference.toml, value for value: smooth glass (an analytic sphere and a
    flat-shaded triangle ball, tests/data/glass_ball.obj) on a diffuse floor under venice.exr.
    Conventions matched (docs/conventions.md): vertical field of view, box filter, the envmap's
    identity orientation, a rectangle turned to face +y as Lantern's quad."""
    mi, _, _ = _import_mitsuba()
    T = mi.ScalarTransform4f
    root = GLASS_SCENE.parent
    glass = {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(max_depth)},
        "sensor": {"type": "perspective", "fov": 30.0, "fov_axis": "y",
                   "to_world": T().look_at(origin=[0.0, 0.9, 3.2], target=[0.0, 0.45, 0.0], up=[0.0, 1.0, 0.0]),
                   "film": {"type": "hdrfilm", "width": int(width), "height": int(height),
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 16}},
        "environment": {"type": "envmap", "filename": str(root.parents[1] / "assets" / "envmaps" / "venice.exr")},
        "floor": {"type": "rectangle", "to_world": T().rotate([1.0, 0.0, 0.0], -90.0).scale([2.0, 2.0, 1.0]),
                  "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.6, 0.4, 0.3]}}},
        "sphere": {"type": "sphere", "center": [-0.45, 0.4, 0.0], "radius": 0.4, "bsdf": glass},
        "ball": {"type": "obj", "filename": str(root / "glass_ball.obj"), "face_normals": True,
                 "to_world": T().translate([0.45, 0.4, 0.0]), "bsdf": glass},
    }


STRESS_SCENE = Path(__file__).resolve().parents[2] / "assets" / "scenes" / "stress.toml"


def stress_scene_dict(width: int = 320, height: int = 180, max_depth: int = 8) -> dict:
    """assets/scenes/stress.toml in Mitsuba's terms: the same million-triangle terrain (Lantern's
    own generator, with its vertex normals), spheres, camera (vertical field of view, box filter)
    and sunset.exr (identity orientation, as in glass_scene_dict). The materials are Mitsuba's
    nearest: `principled` for the principled earth (specular 0.5 = ior 1.5), a smooth `dielectric`
    of ior 1.5, and for the gold conductor (base colour and GGX roughness 0.15 in Lantern, which
    adds Kulla-Conty multiple scattering) Mitsuba's `roughconductor` of measured gold ("Au") with
    alpha 0.15^2. So the two images differ a little, and the mesh-heavy comparison reads each
    renderer against its own reference (renderer/bench/integrators.py)."""
    mi, _, _ = _import_mitsuba()
    from renderer.scene.generators import generate

    T = mi.ScalarTransform4f
    positions, indices, normals = generate("terrain", (("resolution", 708), ("size", 40.0), ("height", 3.0),
                                                       ("seed", 7)))
    terrain = mi.Mesh("terrain", len(positions), len(indices), has_vertex_normals=True)
    params = mi.traverse(terrain)
    params["vertex_positions"] = np.ascontiguousarray(positions, np.float32).ravel()
    params["vertex_normals"] = np.ascontiguousarray(normals, np.float32).ravel()
    params["faces"] = np.ascontiguousarray(indices, np.uint32).ravel()
    params.update()
    earth = {"type": "principled", "base_color": {"type": "rgb", "value": [0.36, 0.3, 0.22]}, "metallic": 0.0,
             "roughness": 0.85, "specular": 0.5}
    terrain.set_bsdf(mi.load_dict(earth))
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(max_depth)},
        "sensor": {"type": "perspective", "fov": 45.0, "fov_axis": "y",
                   "to_world": T().look_at(origin=[0.0, 2.2, 17.0], target=[0.0, 0.6, 0.0], up=[0.0, 1.0, 0.0]),
                   "film": {"type": "hdrfilm", "width": int(width), "height": int(height), "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 16}},
        "environment": {"type": "envmap", "filename": str(STRESS_SCENE.parents[1] / "envmaps" / "sunset.exr")},
        "terrain": terrain,
        "glass": {"type": "sphere", "center": [-2.0, 0.86, 4.0], "radius": 1.2,
                  "bsdf": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}},
        "gold": {"type": "sphere", "center": [3.0, 0.74, 0.0], "radius": 1.5,
                 "bsdf": {"type": "roughconductor", "material": "Au", "distribution": "ggx", "alpha": 0.15 ** 2}},
    }


def render_scene(scene, spp: int, seed: int = 0) -> np.ndarray:
    """One render of a loaded Mitsuba scene: linear RGB float32 (height, width, 3), row 0 = top."""
    mi, _, _ = _import_mitsuba()
    image = np.array(mi.render(scene, spp=int(spp), seed=int(seed)), dtype=np.float32)
    return np.ascontiguousarray(image[..., :3])


def samples_taken(scene) -> int:
    """The samples per pixel of the scene's last render: what its sampler made of the spp asked
    for (Mitsuba's multijitter rounds it up to a product of two near-equal factors: 32 -> 35)."""
    return int(scene.sensors()[0].sampler().sample_count())


def render_cornell_box(width: int = 256, height: int = 256, spp: int = 64, seed: int = 0,
                       threads: int | None = None, warmup: bool = True, max_depth: int = 8) -> MitsubaRender:
    """Render Mitsuba's Cornell box (box filter) and time it.

    With `warmup`, a 1-spp render first compiles the JIT kernels (LLVM variants), so `seconds`
    measures rendering only, as Lantern's benchmarks time their kernels after compilation.
    """
    set_threads(threads)
    scene = load_cornell_box(width, height, max_depth)
    if warmup:
        render_scene(scene, 1, seed + 1)
    start = time.perf_counter()
    image = render_scene(scene, spp, seed)  # np.array() waits for the JIT's asynchronous work
    seconds = time.perf_counter() - start
    return MitsubaRender(image, seconds, width * height * spp / seconds if seconds > 0 else float("inf"))


def mitsuba_reference(config, size: tuple[int, int], max_depth: int) -> dict:
    """Mitsuba's reference image (mean of independent passes) and its noise floor (from the spread
    of the passes: var of the mean = sample variance of the pass images / passes)."""
    from renderer.bench.convergence import noise_floor

    set_threads(config.mitsuba_threads)
    scene = load_cornell_box(size[0], size[1], max_depth)
    passes = max(2, config.mitsuba_reference_spp // config.mitsuba_pass_spp)
    t0 = time.perf_counter()
    images = [render_scene(scene, config.mitsuba_pass_spp, seed=config.reference_seed + k).astype(np.float64)
              for k in range(passes)]
    seconds = time.perf_counter() - t0
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    var_of_mean = stack.var(axis=0, ddof=1) / passes
    return {"scene": scene, "image": mean.astype(np.float32), "spp": passes * config.mitsuba_pass_spp,
            "passes": passes, "seconds": seconds, "noise_floor": noise_floor(mean, var_of_mean)}

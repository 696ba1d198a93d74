"""`python app.py bench mitsuba-tests`: Mitsuba 3's own render tests, passed by Lantern.

`--data DIR` names a checkout of the public mitsuba-data repository (or its tests/scenes folder). Every scene
`tests/scenes/<group>/<name>_<integrator>.xml` with an RGB reference `refs/<name>_ref_rgb.exr` and
its per-sample variance `refs/<name>_ref_rgb_var.exr` is opened by Lantern's Mitsuba reader and
rendered at the reference's resolution with Mitsuba's sample budget (2 million samples an image,
so 868 spp at 48x48), seed 0, with the scene's own integrator and depth. It is judged by the rule
of Mitsuba's src/render/tests/test_renders.py:
    * both images in CIE XYZ (Mitsuba's linear sRGB -> XYZ matrix), the variance image with them;
    * per pixel and channel z = |image - reference| sqrt(spp / max(variance, 1e-4)), p = 2 (1 - Phi(z));
    * a pixel channel passes where p > 1 - (1 - 0.01)^(1 / pixels) (Sidak's correction at the 1% level);
    * the scene passes when at least 99.75% of the pixels' channels pass.
The table gives each scene's verdict, the share of failing pixel channels, the image means (Lantern's
over the reference's), the render and load times, and for a failure what the reader left out (its
warnings), so a failure reads as "not built yet" or "built and wrong". Writes bench_mitsuba_tests.json
under the output folder, and the error map of each failing scene as a PNG.
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from renderer.bench.common import log, print_table, report_header, load_average, write_json

SAMPLE_BUDGET = 2_000_000  # samples an image, as Mitsuba's render tests take
SIGNIFICANCE = 0.01
PASS_FRACTION = 0.9975
VARIANCE_FLOOR = 1e-4
SRGB_TO_XYZ = np.array([[0.412453, 0.357580, 0.180423],
                        [0.212671, 0.715160, 0.072169],
                        [0.019334, 0.119193, 0.950227]])  # Mitsuba's srgb_to_xyz
QUICK_SCENES = ("test_arealight", "test_constant", "scene", "test_roughdielectric", "test_homo_null_envmap")


@dataclass(frozen=True)
class TestScene:
    scene: Path
    reference: Path
    variance: Path

    @property
    def name(self) -> str:
        return f"{self.scene.parent.name}/{self.scene.stem}"


def find_test_scenes(data: Path) -> tuple[list[TestScene], list[Path]]:
    """(scenes with an RGB reference, scenes without one) under DIR or DIR/tests/scenes."""
    root = data / "tests" / "scenes" if (data / "tests" / "scenes").is_dir() else data
    found, missing = [], []
    for scene in sorted(root.glob("*/*.xml")):
        stem = scene.stem.rsplit("_", 1)[0]  # test_arealight_path -> test_arealight
        reference = scene.parent / "refs" / f"{stem}_ref_rgb.exr"
        variance = scene.parent / "refs" / f"{stem}_ref_rgb_var.exr"
        if reference.exists() and variance.exists():
            found.append(TestScene(scene, reference, variance))
        else:
            missing.append(scene)
    return found, missing


def mitsuba_verdict(image: np.ndarray, spp: int, reference: np.ndarray, variance: np.ndarray) -> dict:
    """Mitsuba's render-test rule on (H, W, 3) linear RGB images; returns the verdict and its parts."""
    from scipy import stats

    to_xyz = lambda rgb: np.asarray(rgb, np.float64) @ SRGB_TO_XYZ.T  # noqa: E731
    image, reference, variance = to_xyz(image), to_xyz(reference), to_xyz(variance)
    z = np.abs(image - reference) * np.sqrt(spp / np.maximum(variance, VARIANCE_FLOOR))
    p_value = 2.0 * stats.norm.sf(z)
    pixels = image.shape[0] * image.shape[1]
    level = -np.expm1(np.log1p(-SIGNIFICANCE) / pixels)
    success = p_value > level
    passed_fraction = np.count_nonzero(success) / 3 / pixels
    return {"passed": bool(passed_fraction >= PASS_FRACTION), "failing_fraction": 1.0 - passed_fraction,
            "min_p": float(p_value.min()), "level": float(level), "failing": ~success.all(axis=-1)}


def render_scene(test: TestScene, spp_override: int | None = None) -> dict:
    """Load, render and judge one scene; every failure to load or render is the row's note."""
    from renderer.camera import CameraFrame
    from renderer.output.image_io import read_exr
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any

    reference = read_exr(test.reference)[..., :3]
    variance = read_exr(test.variance)[..., :3]
    height, width = reference.shape[:2]
    spp = spp_override or max(1, SAMPLE_BUDGET // (width * height))
    row = {"scene": test.name, "size": f"{width}x{height}", "spp": spp, "verdict": None, "failing_percent": None,
           "mean_ratio_rgb": None, "render_s": None, "warnings": 0}
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            scene = load_any(test.scene)
        except Exception as error:  # noqa: BLE001 - a scene the reader refuses is a row, not a crash
            return {**row, "verdict": "not loaded", "note": str(error)}
    row["load_s"] = time.perf_counter() - t0
    row["left_out"] = [str(w.message).split(": ", 2)[-1] for w in caught]
    row["warnings"] = len(row["left_out"])
    if scene.render.image_size != (width, height):
        return {**row, "verdict": "size differs", "note": "the scene is {}x{}".format(*scene.render.image_size)}
    renderer = Renderer(scene, (width, height))
    camera = CameraFrame.from_spec(scene.camera)
    t0 = time.perf_counter()
    renderer.render(camera, 1, scene.render.integrator, max_depth=scene.render.max_depth, seed=1)  # compiles
    row["compile_s"] = time.perf_counter() - t0
    renderer.reset()
    t0 = time.perf_counter()
    renderer.render(camera, spp, scene.render.integrator, max_depth=scene.render.max_depth, seed=0)
    image = renderer.image()
    row["render_s"] = time.perf_counter() - t0
    judged = mitsuba_verdict(image, spp, reference, variance)
    ratios = [float(a / b) if b > 0 else None for a, b in zip(image.mean(axis=(0, 1)), reference.mean(axis=(0, 1)))]
    row.update(verdict="PASS" if judged["passed"] else "FAIL", failing_percent=100.0 * judged["failing_fraction"],
               mean_ratio_rgb=" ".join("-" if r is None else f"{r:.3f}" for r in ratios))
    row["_images"] = (image, reference, judged["failing"])
    return row


def write_error_map(row: dict, out_dir: Path) -> Path:
    """Lantern's image, the reference, and the failing pixels (white), side by side."""
    from renderer.output.image_io import write_png
    from renderer.output.tonemap import tonemap_array

    image, reference, failing = row["_images"]
    mark = np.repeat(failing[..., None].astype(np.uint8) * 255, 3, axis=-1)
    strip = np.concatenate([tonemap_array(image, 0.0, "none"), tonemap_array(reference, 0.0, "none"), mark], axis=1)
    path = out_dir / f"mitsuba_tests_{row['scene'].replace('/', '_')}.png"
    write_png(path, strip)
    return path


def run(quick: bool = False, out_dir: Path = Path("reports"), data: Path | None = None, only: str | None = None,
        spp: int | None = None) -> int:
    if data is None:
        raise ValueError("bench mitsuba-tests needs --data DIR: a checkout of the mitsuba-data repository")
    data = Path(data)
    if not data.is_dir():
        raise ValueError(f"--data {data}: not a folder")
    from renderer.runtime.arch import init_taichi

    found, missing = find_test_scenes(data)
    if only:
        found = [t for t in found if only in t.name]
    elif quick:
        found = [t for t in found if t.scene.stem.rsplit("_", 1)[0] in QUICK_SCENES]
    if not found:
        raise ValueError(f"--data {data}: no scene with an RGB reference under tests/scenes")
    import taichi as ti

    load_before = load_average()
    out_dir.mkdir(parents=True, exist_ok=True)
    rows = []
    for test in found:
        log(f"[{test.name}] ...")
        # A fresh Taichi runtime per scene: one runtime holds a bounded number of field trees, and
        # forty scenes' worth of fields in one crashed inside Taichi. Kernels come from the cache.
        init_taichi("cpu")
        try:
            row = render_scene(test, spp)
        finally:
            ti.reset()
        if row.get("verdict") == "FAIL":
            row["error_map"] = str(write_error_map(row, out_dir))
        row.pop("_images", None)
        rows.append(row)
    passed = sum(r["verdict"] == "PASS" for r in rows)
    print_table(["scene", "size", "spp", "verdict", "failing %", "mean ratio (R, G, B)", "render s", "left out"],
                [[r["scene"], r["size"], r["spp"], r["verdict"],
                  "" if r["failing_percent"] is None else f"{r['failing_percent']:.2f}", r["mean_ratio_rgb"] or "",
                  "" if r["render_s"] is None else f"{r['render_s']:.1f}",
                  f"{r['warnings']} warnings" if r["warnings"] else r.get("note", "")]
                 for r in rows], title=f"Mitsuba 3's render tests: {passed} of {len(rows)} pass")
    report = report_header("mitsuba-tests", quick, load_before, data=str(data), sample_budget=SAMPLE_BUDGET,
                           rule={"significance": SIGNIFICANCE, "pass_fraction": PASS_FRACTION,
                                 "variance_floor": VARIANCE_FLOOR})
    report.update(passed=passed, scenes=len(rows), without_reference=[str(p) for p in missing], results=rows)
    path = write_json(out_dir / "bench_mitsuba_tests.json", report)
    print(f"wrote {path}")
    return 0

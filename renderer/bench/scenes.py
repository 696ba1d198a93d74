"""`python app.py bench scenes --data DIR --time S`: the standard scenes of rendering research
(Bitterli's set in pbrt-v4 form, e.g. a checkout of gonsolo/bitterli), rendered by Lantern beside
Tungsten's reference renders.

Every scene folder `DIR/<name>` holding a pbrt-v4 file (`<name>/pbrt/scene-v4.pbrt`, else the first
`.pbrt` found under the folder) is opened, rendered at a size of the scene's own aspect ratio (its
long side LONG_SIDE pixels; QUICK_LONG_SIDE with --quick) for S seconds of sampling after one
compiling sample, with the scene's integrator but paths of any length (MAX_DEPTH), and set beside
`TungstenRender.exr` where the folder has one. Per scene: load
time, the reader's warnings (what it left out: files missing from the copy, unsupported plugins),
triangles and the device bytes per triangle (BVH, triangles, their attributes), samples per
second, the image means per channel and their ratio to the reference's (the reference at its own
size: a mean does not depend on resolution), and a strip of the two images (Lantern's left, the
reference reduced to the same size right) as a PNG. Targets: every scene whose files are complete
renders; on the scenes whose materials Tungsten and pbrt-v4 define alike (MATCHED) the mean of
every channel is within TARGET of Tungsten's. Writes bench_scenes.json and the strips under the
output folder.
"""
from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np

from renderer.bench.common import describe_error, load_average, log, print_table, report_header, write_json

LONG_SIDE = 160
QUICK_LONG_SIDE = 64
DEFAULT_SECONDS = 20.0
TARGET = 0.03  # the largest relative difference of a channel's mean on the MATCHED scenes
MATCHED = ("cornell-box", "veach-mis", "veach-bidir", "water-caustic", "volumetric-caustic")
CHUNK_SPP = 4  # samples per pixel between looks at the clock
# Paths are not cut (Russian roulette ends them): Tungsten's references follow 64 bounces, as good as
# unlimited, where this copy's files often ask for less (cornell-box's maxdepth 4, noted "65").
MAX_DEPTH = -1


def find_scenes(data: Path) -> list[tuple[str, Path, Path | None]]:
    """(name, scene file, reference or None) of every scene folder under `data` with a .pbrt file."""
    found = []
    for folder in sorted(p for p in data.iterdir() if p.is_dir()):
        preferred = folder / "pbrt" / "scene-v4.pbrt"
        candidates = [preferred] if preferred.is_file() else sorted(folder.rglob("*.pbrt"))
        if not candidates:
            continue
        references = sorted(folder.rglob("TungstenRender.exr"))
        found.append((folder.name, candidates[0], references[0] if references else None))
    return found


def bench_size(scene_size: tuple[int, int], long_side: int) -> tuple[int, int]:
    """The scene's aspect ratio with its long side `long_side` pixels (each side at least 8)."""
    w, h = scene_size
    s = long_side / max(w, h)
    return max(8, round(w * s)), max(8, round(h * s))


def reduce_to(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """An (H, W, 3) image averaged over blocks down to (width, height) `size` (each output pixel the
    mean of the input pixels whose centres fall in it)."""
    h, w = image.shape[:2]
    width, height = size
    rows = np.minimum((np.arange(h) + 0.5) * height // h, height - 1).astype(int)
    cols = np.minimum((np.arange(w) + 0.5) * width // w, width - 1).astype(int)
    total = np.zeros((height, width, 3))
    count = np.zeros((height, width, 1))
    np.add.at(total, (rows[:, None], cols[None, :]), image[..., :3])
    np.add.at(count, (rows[:, None], cols[None, :]), 1.0)
    return total / np.maximum(count, 1.0)


def comparable_reference(reference: np.ndarray, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """(The reference reduced to the bench's `size`, the (height, width) mask of bench pixels both
    means keep). A reference pixel that is not finite (water-caustic's light overflowed its half
    floats) is left out of both means with the 3x3 bench pixels around it: what overflowed is a
    small emitter seen directly, which the two images place a fraction of a pixel apart."""
    finite = np.isfinite(reference).all(axis=-1)
    whole = reduce_to(np.repeat(finite[..., None], 3, axis=-1).astype(np.float64), size)[..., 0] == 1.0
    padded = np.pad(~whole, 1)
    kept = ~np.any([padded[1 + dy:padded.shape[0] - 1 + dy, 1 + dx:padded.shape[1] - 1 + dx]
                    for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=0)
    return reduce_to(np.where(finite[..., None], reference, 0.0), size), kept


def render_scene(name: str, path: Path, reference_path: Path | None, seconds: float, long_side: int,
                 with_mitsuba: bool = False) -> dict:
    """One scene's row (and its images under "_images")."""
    from renderer.camera import CameraFrame
    from renderer.output.image_io import read_exr
    from renderer.renderer import Renderer
    from renderer.scene.catalog import load_any

    row = {"scene": name, "file": str(path), "verdict": None, "warnings": 0, "left_out": []}
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            scene = load_any(path)
        except Exception as error:  # noqa: BLE001 - a scene the reader refuses is a row, not a crash
            return {**row, "verdict": "not loaded", "note": describe_error(error)}
    row["left_out"] = [str(w.message) for w in caught]
    row["warnings"] = len(row["left_out"])
    size = bench_size(scene.render.image_size, long_side)
    try:
        renderer = Renderer(scene, size)
        camera = CameraFrame.from_spec(scene.camera)
        row["load_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        renderer.render(camera, 1, scene.render.integrator, max_depth=MAX_DEPTH, seed=1)  # compiles
        row["compile_s"] = time.perf_counter() - t0
        renderer.reset()
        spp = 0
        t0 = time.perf_counter()
        while spp == 0 or time.perf_counter() - t0 < seconds:
            renderer.render(camera, CHUNK_SPP, scene.render.integrator, max_depth=MAX_DEPTH, seed=spp)
            spp += CHUNK_SPP
        image = renderer.image().astype(np.float64)
        row["render_s"] = time.perf_counter() - t0
    except Exception as error:  # noqa: BLE001 - a scene that fails to render is a row too
        return {**row, "verdict": "not rendered", "note": describe_error(error)}
    geometry_bytes = renderer.geometry.device_bytes() if hasattr(renderer.geometry, "device_bytes") else None
    data = getattr(renderer.geometry, "data", None)
    triangles = 0 if data is None else len(data.tri_vertices)
    row.update(size=f"{size[0]}x{size[1]}", spp=spp, samples_per_s=spp * size[0] * size[1] / row["render_s"],
               triangles=triangles, verdict="rendered",
               bytes_per_triangle=(geometry_bytes["total"] / triangles) if geometry_bytes and triangles else None,
               mean_rgb=[float(v) for v in image.mean(axis=(0, 1))])
    reference = None
    if reference_path is not None:
        reference = read_exr(reference_path)[..., :3].astype(np.float64)
        non_finite = int(np.count_nonzero(~np.isfinite(reference).all(axis=-1)))
        reference, kept = comparable_reference(reference, size)
        row["_kept"] = kept
        if non_finite:
            row["reference_non_finite_pixels"] = non_finite
            row["bench_pixels_left_out"] = int(np.count_nonzero(~kept))
        ref_mean = reference[kept].mean(axis=0)
        row["reference_mean_rgb"] = [float(v) for v in ref_mean]
        row["mean_ratio_rgb"] = [float(a / b) if b > 0 else None for a, b in zip(image[kept].mean(axis=0), ref_mean)]
        if name in MATCHED:
            within = all(r is not None and abs(r - 1.0) <= TARGET for r in row["mean_ratio_rgb"])
            row["verdict"] = "PASS" if within else "FAIL"
    row["_images"] = (image, reference)
    if with_mitsuba:
        from renderer.bench.scenes_mitsuba import mitsuba_side

        theirs = mitsuba_side(scene, size, MAX_DEPTH, seconds)
        image_m = theirs.pop("_image", None)
        row.update(theirs)
        if image_m is not None:
            kept = row.get("_kept", np.ones(image.shape[:2], bool))
            row["mitsuba_mean_rgb"] = [float(v) for v in image_m[kept].mean(axis=0)]
            row["mitsuba_to_lantern_rgb"] = [float(m / a) if a > 0 else None
                                             for m, a in zip(image_m[kept].mean(axis=0), image[kept].mean(axis=0))]
            if reference is not None:
                row["mitsuba_mean_ratio_rgb"] = [float(m / b) if b > 0 else None for m, b in
                                                 zip(image_m[kept].mean(axis=0), reference[kept].mean(axis=0))]
    row.pop("_kept", None)
    return row


def write_strip(row: dict, out_dir: Path) -> Path:
    """Lantern's image (left) beside the reference reduced to its size (right), both tonemapped alike."""
    from renderer.output.image_io import write_png
    from renderer.output.tonemap import tonemap_array

    image, reference = row["_images"]
    parts = [tonemap_array(image.astype(np.float32), 0.0, "aces")]
    if reference is not None:
        parts.append(tonemap_array(reference.astype(np.float32), 0.0, "aces"))
    path = out_dir / f"scenes_{row['scene']}.png"
    write_png(path, np.concatenate(parts, axis=1))
    return path


def run(quick: bool = False, out_dir: Path = Path("reports"), data: Path | None = None, only: str | None = None,
        seconds: float | None = None, mitsuba: bool = False) -> int:
    if data is None:
        raise ValueError("bench scenes needs --data DIR: a folder of scene folders in pbrt-v4 form "
                         "(e.g. a checkout of gonsolo/bitterli)")
    data = Path(data)
    if not data.is_dir():
        raise ValueError(f"--data {data}: not a folder")
    found = [s for s in find_scenes(data) if not only or only in s[0]]
    if not found:
        raise ValueError(f"--data {data}: no scene folder with a .pbrt file")
    import taichi as ti

    from renderer.runtime.arch import init_taichi

    seconds = (2.0 if quick else DEFAULT_SECONDS) if seconds is None else seconds
    long_side = QUICK_LONG_SIDE if quick else LONG_SIDE
    load_before = load_average()
    out_dir.mkdir(parents=True, exist_ok=True)
    rows = []
    for name, path, reference in found:
        log(f"[{name}] ...")
        init_taichi("cpu")  # a fresh runtime per scene (bounded field trees; kernels come from the cache)
        try:
            row = render_scene(name, path, reference, seconds, long_side, with_mitsuba=mitsuba)
        finally:
            ti.reset()
        if "_images" in row:
            row["strip"] = str(write_strip(row, out_dir))
            row.pop("_images")
        rows.append(row)
    judged = [r for r in rows if r["scene"] in MATCHED]
    passed = sum(r["verdict"] == "PASS" for r in judged)
    print_table(["scene", "size", "spp", "verdict", "mean ratio (R, G, B)", "load s", "Msamples/s", "B/triangle",
                 "left out"],
                [[r["scene"], r.get("size", ""), r.get("spp", ""), r["verdict"],
                  " ".join("-" if v is None else f"{v:.3f}" for v in r.get("mean_ratio_rgb") or []),
                  f"{r['load_s']:.1f}" if "load_s" in r else "",
                  f"{r['samples_per_s'] / 1e6:.2f}" if "samples_per_s" in r else "",
                  f"{r['bytes_per_triangle']:.0f}" if r.get("bytes_per_triangle") else "",
                  f"{r['warnings']} warnings" if r["warnings"] else r.get("note", "")]
                 for r in rows],
                title=f"Research scenes: {len(rows)} found, {sum('spp' in r for r in rows)} rendered; "
                      f"{passed} of {len(judged)} matched scenes within {100 * TARGET:.0f}% of Tungsten's means")
    if mitsuba:
        print_table(["scene", "Mitsuba / Tungsten (R, G, B)", "Mitsuba / Lantern", "Mitsuba Msamples/s", "note"],
                    [[r["scene"], " ".join(f"{v:.3f}" for v in r.get("mitsuba_mean_ratio_rgb") or []),
                      " ".join(f"{v:.3f}" for v in r.get("mitsuba_to_lantern_rgb") or []),
                      f"{r['mitsuba_samples_per_s'] / 1e6:.2f}" if "mitsuba_samples_per_s" in r else "",
                      r.get("mitsuba_note") or next((n for n in r.get("mitsuba_notes") or [] if "left out" in n), "")]
                     for r in rows],
                    title="The same scenes as read, rendered by Mitsuba 3 for the same time")
    report = report_header("scenes", quick, load_before, data=str(data), seconds=seconds, long_side=long_side,
                           target=TARGET, matched=list(MATCHED), mitsuba=mitsuba)
    report.update(results=rows, passed=passed, judged=len(judged))
    path = write_json(out_dir / "bench_scenes.json", report)
    print(f"wrote {path}")
    return 0

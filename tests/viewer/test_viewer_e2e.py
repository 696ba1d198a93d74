"""End to end, as a person uses it: the real viewer window under Xvfb, driven by xdotool.

Starts `app.py view showcase --size 320x180` on a private X display (software Vulkan draws the
GGUI window), waits for its first image, hides the HUD ('h'), holds 'w', drags with the left
button, switches the integrator ('i') and the scene ('n'), saves a screenshot ('p') and quits
(Escape). Grabs of the X screen before and after each move show the view changed as the input
asks: 'w' moves the camera forward, so the view grows about its centre; a drag to the right turns
it right, so the view slides left. Then checks the screenshot files and the exit code.
"""
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from renderer.integrators import integrator_names
from renderer.scene.catalog import scene_names

pytestmark = pytest.mark.display

ROOT = Path(__file__).resolve().parents[2]
SIZE = (320, 180)
TIMEOUT = 150  # seconds for the whole session; cold kernel compiles dominate it
# Not blank: see MIN_PIXEL_STD in test_window_offscreen.py (8-bit values; 0 for a constant image).
MIN_PIXEL_STD = 10.0
TOOLS = ("Xvfb", "xdotool", "import")


def free_display() -> int:
    for n in range(90, 400):
        if not os.path.exists(f"/tmp/.X{n}-lock") and not os.path.exists(f"/tmp/.X11-unix/X{n}"):
            return n
    pytest.skip("no free X display number")


@pytest.fixture
def xserver():
    missing = [tool for tool in TOOLS if shutil.which(tool) is None]
    if missing:
        pytest.skip(f"missing {', '.join(missing)} (Debian packages xvfb, xdotool, imagemagick)")
    n = free_display()
    server = subprocess.Popen(["Xvfb", f":{n}", "-screen", "0", "800x600x24", "-nolisten", "tcp"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 10
    while not os.path.exists(f"/tmp/.X11-unix/X{n}"):
        if server.poll() is not None or time.monotonic() > deadline:
            server.kill()
            pytest.skip("Xvfb did not start")
        time.sleep(0.05)
    env = dict(os.environ, DISPLAY=f":{n}")
    yield env
    server.terminate()
    try:
        server.wait(5)
    except subprocess.TimeoutExpired:
        server.kill()


def xdo(env, *args, timeout=30):
    return subprocess.run(["xdotool", *map(str, args)], env=env, capture_output=True, text=True, timeout=timeout)


def grab(env, path: Path) -> np.ndarray:
    """The whole X screen via ImageMagick, as uint8 (H, W, 3)."""
    import imageio.v3 as iio

    # PNG24: ImageMagick would write a grey-scale PNG for a screen that happens to be grey.
    subprocess.run(["import", "-window", "root", f"PNG24:{path}"], env=env, check=True, timeout=20,
                   capture_output=True)
    return iio.imread(path)[:, :, :3]


def window_pixels(screen: np.ndarray, geometry: dict) -> np.ndarray:
    x, y = geometry["X"], geometry["Y"]
    return screen[y:y + SIZE[1], x:x + SIZE[0]]


# Two grabs of a still view this close (mean absolute difference of 8-bit values) show the same
# image: the normals view converges within a few samples, only its anti-aliased edges change.
STILL_DIFFERENCE = 1.0
# A move changes the view by far more than that (tens of levels where objects shift).
MOVED_DIFFERENCE = 8.0


def still_view(env, path: Path, geometry: dict, viewer, deadline: float) -> np.ndarray:
    """The window's pixels once the view has stopped changing (moving frames are at a reduced
    resolution; then still frames accumulate): two grabs in a row that agree."""
    previous = None
    while True:
        assert viewer.poll() is None, "the viewer ended"
        assert time.monotonic() < deadline, "the view did not settle within the time limit"
        pixels = window_pixels(grab(env, path), geometry).astype(np.float64)
        if previous is not None and np.abs(pixels - previous).mean() < STILL_DIFFERENCE:
            return pixels
        previous = pixels
        time.sleep(0.3)


def zoom_about_centre(image: np.ndarray, scale: float) -> np.ndarray:
    """The view of a camera moved towards the centre of the image, for points at one depth: the
    image magnified `scale` times about its centre (nearest pixel)."""
    h, w = image.shape[:2]
    rows = np.clip(np.round((h - 1) / 2 + (np.arange(h) - (h - 1) / 2) / scale).astype(int), 0, h - 1)
    cols = np.clip(np.round((w - 1) / 2 + (np.arange(w) - (w - 1) / 2) / scale).astype(int), 0, w - 1)
    return image[rows][:, cols]


def best_zoom(before: np.ndarray, after: np.ndarray) -> float:
    """The magnification about the centre that best maps `before` onto `after` (the middle half of
    the image compared, which every scale tried maps from inside the image)."""
    h, w = before.shape[:2]
    middle = (slice(h // 4, 3 * h // 4), slice(w // 4, 3 * w // 4))
    scales = np.round(np.arange(0.50, 3.0001, 0.02), 2)
    errors = [np.abs(zoom_about_centre(before, s)[middle] - after[middle]).mean() for s in scales]
    return float(scales[int(np.argmin(errors))])


def best_shift(before: np.ndarray, after: np.ndarray, reach: tuple[int, int] = (60, 30)) -> tuple[int, int]:
    """(dx, dy) in pixels such that after[y, x] best matches before[y - dy, x - dx]: how far the
    view slid (positive: right, down). Compared in grey levels on the middle of `after` (where a
    small turn of the camera is a slide; towards the edges it also stretches the view)."""
    before, after = before.mean(axis=2), after.mean(axis=2)
    h, w = before.shape
    rx, ry = reach
    y0, y1, x0, x1 = ry, h - ry, rx, w - rx  # every shift tried reads `before` inside the image
    middle = after[y0:y1, x0:x1]
    errors = {(dx, dy): np.abs(middle - before[y0 - dy:y1 - dy, x0 - dx:x1 - dx]).mean()
              for dy in range(-ry, ry + 1) for dx in range(-rx, rx + 1)}
    return min(errors, key=errors.get)


def test_viewer_under_xvfb(xserver, tmp_path):
    env = dict(xserver, LANTERN_SCREENSHOT_DIR=str(tmp_path / "shots"))
    log = open(tmp_path / "viewer.log", "w")
    # Run from tmp_path: imgui writes its imgui.ini into the working directory.
    # The test is about the window, the input and the files, not light transport: start on the
    # normals view, whose kernels compile in seconds (`i` then moves to albedo, `n` to the next
    # scene with it), so a cold kernel cache cannot push it past its time limit.
    viewer = subprocess.Popen([sys.executable, str(ROOT / "app.py"), "view", "showcase", "--size",
                               f"{SIZE[0]}x{SIZE[1]}", "--integrator", "normals"],
                              cwd=tmp_path, env=env, stdout=log, stderr=log)
    start = time.monotonic()
    try:
        found = xdo(env, "search", "--sync", "--name", "Lantern", timeout=60)
        assert found.returncode == 0 and found.stdout.split(), f"no window: {(tmp_path / 'viewer.log').read_text()}"
        window = found.stdout.split()[0]
        geometry = dict(re.findall(r"(\w+)=(\d+)", xdo(env, "getwindowgeometry", "--shell", window).stdout))
        geometry = {k: int(v) for k, v in geometry.items()}
        xdo(env, "windowfocus", "--sync", window)

        # The first frame shows a 'compiling...' notice on black; wait for the rendered image
        # (the right edge: the HUD covers the left part of so small a window).
        while True:
            assert viewer.poll() is None, (tmp_path / "viewer.log").read_text()
            assert time.monotonic() - start < TIMEOUT, "no image within the time limit"
            pixels = window_pixels(grab(env, tmp_path / "screen.png"), geometry)
            if pixels[:, -100:].std() > MIN_PIXEL_STD:
                break
            time.sleep(0.5)

        xdo(env, "mousemove", "--window", window, 280, 90)
        xdo(env, "key", "h")  # the HUD off: the whole window shows the view
        deadline = start + TIMEOUT
        before = still_view(env, tmp_path / "screen_before.png", geometry, viewer, deadline)

        xdo(env, "keydown", "w")  # forward, towards the centre of the view, at 2 m/s
        time.sleep(0.6)
        xdo(env, "keyup", "w")
        forward = still_view(env, tmp_path / "screen_forward.png", geometry, viewer, deadline)
        assert np.abs(forward - before).mean() > MOVED_DIFFERENCE, "'w' did not change the view"
        # Showcase's objects, about 5 m ahead, come a metre or two closer (how far depends on when
        # the viewer's frames saw the key go down and up): the view grows about its centre, by
        # ~1.5 here (backwards it would shrink). 0.4 m, a third of the least move, would give 1.08.
        scale = best_zoom(before, forward)
        assert scale >= 1.08, f"'w': the view grew {scale} times about its centre"

        xdo(env, "mousedown", 1)  # a left drag, right and a little down (the HUD is hidden)
        time.sleep(0.3)  # (frames see the button down before the cursor moves)
        for _ in range(5):
            xdo(env, "mousemove_relative", "--", 6, 2)
            time.sleep(0.1)
        time.sleep(0.5)  # (and the last move before the button goes up)
        xdo(env, "mouseup", 1)
        turned = still_view(env, tmp_path / "screen_turned.png", geometry, viewer, deadline)
        assert turned.std() > MIN_PIXEL_STD
        assert np.abs(turned - forward).mean() > MOVED_DIFFERENCE, "the drag did not change the view"
        # 30 pixels right, 10 down, at 0.004 radians a pixel: the camera turns 0.12 rad right and
        # 0.04 down, and the view slides ~30 pixels left (320 pixels span 2 tan(fov_x / 2) = 1.29)
        # and ~10 up (180 span 2 tan(20 deg) = 0.73): (-32, -10) here. A move the viewer missed
        # would leave out 6 and 2 of them.
        dx, dy = best_shift(forward, turned)
        assert -42 <= dx <= -18 and -16 <= dy <= -3, f"the drag slid the view by ({dx}, {dy}) pixels"
        # Keys typed while the viewer compiles are queued and run in order once it is done.
        for key in ("i", "n", "p", "Escape"):
            xdo(env, "key", key)
            time.sleep(0.2)
        code = viewer.wait(max(5, TIMEOUT - (time.monotonic() - start)))
    finally:
        if viewer.poll() is None:
            viewer.kill()
            viewer.wait()
        log.close()
    output = (tmp_path / "viewer.log").read_text()
    assert code == 0, output

    names_in_order = integrator_names()
    integrator = names_in_order[(names_in_order.index("normals") + 1) % len(names_in_order)]
    names = scene_names()
    scene = names[(names.index("showcase") + 1) % len(names)]
    assert f"integrator {integrator}" in output and f"scene {scene}" in output
    shots = tmp_path / "shots"
    pngs, exrs = sorted(shots.glob("*.png")), sorted(shots.glob("*.exr"))
    assert len(pngs) == 1 and len(exrs) == 1, output
    assert re.fullmatch(rf"{scene}_{integrator}_\d{{4}}spp_\d{{8}}-\d{{6}}", pngs[0].stem), pngs[0].name
    assert exrs[0].stem == pngs[0].stem

    import imageio.v3 as iio

    from renderer.output.image_io import read_exr

    png = iio.imread(pngs[0])
    assert png.shape == (SIZE[1], SIZE[0], 3)
    assert png.std() > MIN_PIXEL_STD
    assert np.isfinite(read_exr(exrs[0])).all()
    assert time.monotonic() - start < TIMEOUT


def test_a_warmed_viewer_start_compiles_nothing(xserver, tmp_path):
    """`warm-cache SCENE` (off-screen, one process per scene) leaves in Taichi's offline cache every
    kernel that `view SCENE` at that size then needs, in a window, with its first integrator or
    another one chosen at start: the cache gains no kernel from those viewers."""
    from renderer.runtime.arch import LANTERN_CACHE_FOLDER
    from viewer.cache_warmer import cached_kernels

    env = dict(xserver, TI_OFFLINE_CACHE_FILE_PATH=str(tmp_path / "ticache"))
    cache = tmp_path / "ticache" / LANTERN_CACHE_FOLDER

    def app(*args):
        return subprocess.run([sys.executable, str(ROOT / "app.py"), *args, "--size", "320x180", "--arch", "cpu"],
                              cwd=ROOT, env=env, capture_output=True, text=True, timeout=TIMEOUT)

    warmed = app("warm-cache", "cornell_box", "--integrators", "mis,normals")
    assert warmed.returncode == 0, warmed.stdout + warmed.stderr
    assert "cornell_box / mis: kernels ready in" in warmed.stdout and "cornell_box / normals" in warmed.stdout
    kernels = cached_kernels(cache)
    assert f"cornell_box: {kernels} kernels added to the cache" in warmed.stdout
    # Long enough for still frames past the first round (bands of rows, from partial passes at this
    # size), though the warm-up stopped at each integrator's first image.
    for chosen in ([], ["--integrator", "normals"]):  # the scene's own integrator (mis), or another
        viewed = app("view", "cornell_box", "--frames", "40", *chosen)
        assert viewed.returncode == 0, viewed.stderr
        assert cached_kernels(cache) == kernels, f"view {' '.join(chosen)} compiled kernels the warm-up had not"
    # A scene the warm-up did not open compiles its own (so the count above does see compiles).
    assert app("view", "weekend", "--frames", "12").returncode == 0
    assert cached_kernels(cache) > kernels

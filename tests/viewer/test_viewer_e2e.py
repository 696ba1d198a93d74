"""End to end, as a person uses it: the real viewer window under Xvfb, driven by xdotool.

Starts `app.py view showcase --size 320x180` on a private X display (software Vulkan draws the
GGUI window), waits for its first image, holds 'w', drags with the left button, switches the
integrator ('i') and the scene ('n'), saves a screenshot ('p') and quits (Escape). Then checks
the screenshot files, a screenshot of the X screen, and the exit code.
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
        xdo(env, "keydown", "w")
        time.sleep(0.6)
        xdo(env, "keyup", "w")
        xdo(env, "mousedown", 1)  # a left drag, starting right of the HUD panel
        for _ in range(5):
            time.sleep(0.1)
            xdo(env, "mousemove_relative", "--", 6, 2)
        xdo(env, "mouseup", 1)
        time.sleep(0.3)
        screen = grab(env, tmp_path / "screen_moved.png")
        assert window_pixels(screen, geometry).std() > MIN_PIXEL_STD
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

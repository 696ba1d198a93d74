"""Open each scene of a folder of scene folders in the real viewer window (under Xvfb) and keep a
screenshot of each once it has rendered for a while: the look at every research scene that the
benchmark's numbers do not give. Needs Xvfb and ImageMagick's `import`.

    python scripts/view_scenes.py --data DIR [--seconds 30] [--only TEXT] [--out reports/viewer_scenes]

Needs the Debian packages xvfb, xdotool and imagemagick.

Writes OUT/<scene>.png (the window) and OUT/montage.png, and prints per scene whether the viewer
was still running when the screenshot was taken and what it wrote to stderr last."""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
SIZE = (480, 270)


def start_x() -> tuple[subprocess.Popen, dict]:
    n = next(i for i in range(91, 200) if not os.path.exists(f"/tmp/.X11-unix/X{i}"))
    server = subprocess.Popen(["Xvfb", f":{n}", "-screen", "0", "640x400x24", "-nolisten", "tcp"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 10
    while not os.path.exists(f"/tmp/.X11-unix/X{n}"):
        if server.poll() is not None or time.monotonic() > deadline:
            raise SystemExit("Xvfb did not start")
        time.sleep(0.05)
    return server, dict(os.environ, DISPLAY=f":{n}")


# The title bar of the viewer's "Please wait" box (its HUD is hidden): a row of this colour.
WAIT_BAR = (41, 74, 122)


def _grab(env: dict, out: Path) -> np.ndarray:
    import imageio.v3 as iio

    subprocess.run(["import", "-window", "root", f"PNG24:{out}"], env=env, check=True, timeout=30, capture_output=True)
    return iio.imread(out)[:, :, :3]


def _waiting(screen: np.ndarray, geometry: dict) -> bool:
    window = screen[geometry["Y"]:geometry["Y"] + SIZE[1], geometry["X"]:geometry["X"] + SIZE[0]]
    return bool((np.all(window == WAIT_BAR, axis=-1).sum(axis=1) > SIZE[0] // 3).any())


def view(scene: Path, env: dict, seconds: float, out: Path) -> dict:
    """Runs the viewer on `scene` until its first frames appear, then `seconds` more; grabs the screen."""
    import imageio.v3 as iio

    log = out.with_suffix(".log")
    with open(log, "w") as err:
        viewer = subprocess.Popen([sys.executable, str(ROOT / "app.py"), "view", str(scene), "--size",
                                   f"{SIZE[0]}x{SIZE[1]}"], env=env, stdout=err, stderr=subprocess.STDOUT, cwd=ROOT)
        t0 = time.monotonic()
        # the window exists once kernels are compiled: wait for it (coated scenes compile longest)
        window = ""
        while time.monotonic() - t0 < 600 and viewer.poll() is None and not window:
            found = subprocess.run(["xdotool", "search", "--name", "Lantern"], env=env, capture_output=True, text=True)
            window = found.stdout.split()[0] if found.stdout.split() else ""
            time.sleep(1.0)
        opened = time.monotonic() - t0
        geometry = {"X": 0, "Y": 0}
        if window:
            shell = subprocess.run(["xdotool", "getwindowgeometry", "--shell", window], env=env, capture_output=True,
                                   text=True).stdout
            geometry = {k: int(v) for k, v in (line.split("=") for line in shell.split() if "=" in line)
                        if k in ("X", "Y")}
            for step in (["windowfocus", "--sync", window], ["mousemove", "--window", window, 10, 10], ["key", "h"]):
                subprocess.run(["xdotool", *map(str, step)], env=env, capture_output=True, timeout=30)  # HUD off
        # While its kernels compile the viewer shows a preview under a "Please wait" box (from a few
        # seconds after the window opens): wait for the box to come and go (or not come in a minute).
        # (the box goes between the programs it compiles one after another: gone for three looks)
        seen, clear = False, 0
        while time.monotonic() - t0 < 900 and viewer.poll() is None:
            time.sleep(5.0)
            waiting = _waiting(_grab(env, out), geometry)
            seen = seen or waiting
            clear = 0 if waiting else clear + 1
            if clear >= 3 and (seen or time.monotonic() - t0 > opened + 60.0):
                break
        ready = time.monotonic() - t0
        time.sleep(seconds)
        alive = viewer.poll() is None
        _grab(env, out)
        viewer.terminate()
        try:
            viewer.wait(10)
        except subprocess.TimeoutExpired:
            viewer.kill()
    screen = iio.imread(out)[:, :, :3]
    screen = screen[geometry["Y"]:geometry["Y"] + SIZE[1], geometry["X"]:geometry["X"] + SIZE[0]]
    iio.imwrite(out, screen)
    tail = [line for line in log.read_text().splitlines() if line.strip()][-1:] or [""]
    return {"scene": scene.parent.parent.name if scene.parent.name == "pbrt" else scene.stem, "open_s": opened,
            "ready_s": ready,
            "alive": alive, "screen": screen, "last_line": tail[0][:160], "mean": float(screen.mean())}


def main(argv=None) -> int:
    from renderer.bench.scenes import find_scenes

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, type=Path)
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--only", default="")
    parser.add_argument("--out", type=Path, default=ROOT / "reports" / "viewer_scenes")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    server, env = start_x()
    rows = []
    try:
        for name, path, _ in find_scenes(args.data):
            if args.only and args.only not in name:
                continue
            row = view(path, env, args.seconds, args.out / f"{name}.png")
            rows.append(row)
            print(f"{name:20s} window after {row['open_s']:5.1f} s, settled after {row['ready_s']:5.1f} s, "
                  f"{'running' if row['alive'] else 'ENDED'}, "
                  f"mean grey {row['mean']:5.1f}  {row['last_line']}", flush=True)
    finally:
        server.terminate()
    if rows:
        import imageio.v3 as iio

        tiles = [np.pad(r["screen"], ((2, 2), (2, 2), (0, 0))) for r in rows]
        h, w = max(t.shape[0] for t in tiles), max(t.shape[1] for t in tiles)
        tiles = [np.pad(t, ((0, h - t.shape[0]), (0, w - t.shape[1]), (0, 0))) for t in tiles]
        tiles += [np.zeros_like(tiles[0])] * (-len(tiles) % 4)
        grid = np.concatenate([np.concatenate(tiles[i:i + 4], axis=1) for i in range(0, len(tiles), 4)], axis=0)
        iio.imwrite(args.out / "montage.png", grid)
    return 0 if all(r["alive"] for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())

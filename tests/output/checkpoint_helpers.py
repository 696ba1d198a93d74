"""Checkpoint headers and film states for tests, and a child process's stderr watched as it runs."""
from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

from renderer.output.checkpoint import CheckpointHeader, scene_fingerprint
from renderer.film.accumulation import FilmState
from renderer.scene.catalog import load_any
from renderer.runtime.version import lantern_version

ROOT = Path(__file__).resolve().parents[2]


def header_for(scene_path, **overrides) -> CheckpointHeader:
    """A header as `app.py render SCENE` would write it (24x16, path, seed 0, max depth 3)."""
    scene = load_any(scene_path)
    values = dict(lantern_version=lantern_version(), scene=str(Path(scene_path).resolve()),
                  scene_hash=scene_fingerprint(scene), width=24, height=16, integrator="path",
                  sampler=scene.render.sampler, seed=0, max_depth=3, spp_done=4, slices_in_round=0, spp_target=8, seconds_budget=None,
                  seconds_rendered=1.0, arch="cpu", optimize="compile", out=str(Path(scene_path).with_suffix(".exr")),
                  variance=None, exposure=0.0, tonemapper=None, automatic=False)
    values.update(overrides)
    return CheckpointHeader(**values)


def film_state(width: int, height: int, fill: float) -> FilmState:
    """A state whose every array holds `fill` (counts: int(fill)), so a reader can tell versions apart."""
    return FilmState(np.full((height, width, 3), fill, np.float32), np.full((height, width, 3), fill, np.float32),
                     np.full((height, width), int(fill), np.int32), np.full((height, width), int(fill), np.int32))


class WatchedChild:
    """A child process whose stderr (and stdout) are collected by threads while it runs."""

    def __init__(self, args, cwd=None):
        self.proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=cwd)
        self.out = bytearray()
        self.err = bytearray()
        self._threads = [threading.Thread(target=self._drain, args=(stream, sink), daemon=True)
                         for stream, sink in ((self.proc.stdout, self.out), (self.proc.stderr, self.err))]
        for thread in self._threads:
            thread.start()

    @staticmethod
    def _drain(stream, sink: bytearray) -> None:
        while True:
            chunk = os.read(stream.fileno(), 65536)
            if not chunk:
                return
            sink.extend(chunk)

    def wait_for(self, predicate, timeout: float) -> None:
        """Until predicate(stderr text) holds; fails if the child ends or the time runs out first."""
        deadline = time.monotonic() + timeout
        while not predicate(self.stderr):
            assert self.proc.poll() is None, f"child ended early ({self.proc.returncode}):\n{self.stderr}"
            assert time.monotonic() < deadline, f"timed out waiting; stderr so far:\n{self.stderr}"
            time.sleep(0.005)

    def finish(self, timeout: float) -> int:
        code = self.proc.wait(timeout=timeout)
        for thread in self._threads:
            thread.join(timeout=5)
        return code

    @property
    def stderr(self) -> str:
        return bytes(self.err).decode(errors="replace")

    @property
    def stdout(self) -> str:
        return bytes(self.out).decode(errors="replace")


def python_child(code: str, *args: str) -> list[str]:
    """The command line of a Python child that runs `code` with the project importable."""
    return [sys.executable, "-c", f"import sys; sys.path.insert(0, {str(ROOT)!r})\n{code}", *args]

"""Frame numbers on the command line: the range `--frames A:B`, and the file of each frame, the
run of '#' in `--out` replaced by the frame number, zero-padded to the run's length."""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

DEFAULT_FPS = 24.0
# Frame numbers are 32-bit signed counts elsewhere in Lantern (sample indices): the same cap here.
MAX_FRAME = 2**31 - 1
# Frames of one run: every frame's camera is planned before rendering starts (over 11 hours at 24 fps).
MAX_FRAMES_PER_RUN = 1_000_000
_RANGE = re.compile(r"\s*([^:]*?)\s*:\s*([^:]*?)\s*")
_RUN = re.compile(r"#+")


def parse_frame_range(text: str) -> tuple[int, int]:
    """'A:B' -> (A, B), frames A to B inclusive; ValueError (one line) otherwise."""
    match = _RANGE.fullmatch(text)
    if match is None:
        raise ValueError(f"--frames {text}: expected A:B, the first and last frame (e.g. 0:47)")
    numbers = []
    for part in match.groups():
        if not re.fullmatch(r"[+-]?\d+", part):
            raise ValueError(f"--frames {text}: '{part}' is not a whole frame number")
        numbers.append(int(part))
    first, last = numbers
    if first < 0 or last < 0:
        raise ValueError(f"--frames {text}: frame numbers start at 0")
    if first > last:
        raise ValueError(f"--frames {text}: the first frame {first} is after the last {last}")
    if last > MAX_FRAME:
        raise ValueError(f"--frames {text}: frame numbers go up to {MAX_FRAME}")
    if last - first + 1 > MAX_FRAMES_PER_RUN:
        raise ValueError(f"--frames {text}: at most {MAX_FRAMES_PER_RUN:,} frames in one run")
    return first, last


def turntable_frames(seconds: float, fps: float) -> tuple[int, int]:
    """The frames of one turn: 0 up to the last frame before the turn ends (its time < seconds)."""
    count = max(1, math.ceil(round(seconds * fps, 9)))  # (rounding: 0.1 s at 30 fps is 3 frames, not 4)
    if count > MAX_FRAMES_PER_RUN:
        raise ValueError(f"--turntable {seconds:g} at {fps:g} fps: {count:,} frames, more than the "
                         f"{MAX_FRAMES_PER_RUN:,} of one run (render them in parts with --frames)")
    return 0, count - 1


@dataclass(frozen=True)
class FramePattern:
    """`dir/frame_####.png`: frame 7 is dir/frame_0007.png (frame 12345 dir/frame_12345.png)."""

    pattern: Path

    @classmethod
    def parse(cls, out: Path) -> "FramePattern":
        runs = _RUN.findall(out.name)
        if "#" in str(out.parent):
            found = "a '#' in a folder name"
        elif len(runs) > 1:
            found = f"{len(runs)} runs"
        elif not runs:
            found = "none"
        else:
            return cls(out)
        raise ValueError(f"{out}: --out of an animation needs one run of '#' in the file name, where the "
                         f"frame number goes (e.g. frames/frame_####.png); found {found}")

    @property
    def digits(self) -> int:
        return len(_RUN.search(self.pattern.name).group(0))

    def path(self, frame: int) -> Path:
        name = _RUN.sub(f"{frame:0{self.digits}d}", self.pattern.name, count=1)
        return self.pattern.with_name(name)

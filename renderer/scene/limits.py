"""The memory budget input files are checked against before anything is allocated.

A file declares its size up front: a glTF accessor its count, an image or environment map its
header's width and height, a scene its film. Readers compute what that will cost from the
declared size and compare it with the budget first, so a 200-byte file that asks for gigabytes is
refused in one line (what, how much, the limit, how to raise it) instead of exhausting the
machine. The default is half of the physical memory (or of the container's limit, when lower);
LANTERN_MEMORY_LIMIT or the command line's --memory-limit set it (e.g. 8G, 512M, 2.5G).

A `MemoryLedger` adds up what one scene's files have been charged: a model of a hundred
one-gigabyte accessors is refused as surely as one of a single hundred-gigabyte accessor.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Optional

from renderer.runtime.allocation import allocation_size
from renderer.scene.errors import PathLike, SceneError

ENVIRONMENT_VARIABLE = "LANTERN_MEMORY_LIMIT"
OPTION = "--memory-limit"
DEFAULT_FRACTION = 0.5  # of the physical memory: room for the OS, the compiler and other programs
_UNITS = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}
_CGROUP_LIMIT = Path("/sys/fs/cgroup/memory.max")


def parse_size(text: str) -> int:
    """Bytes of '8G', '512M', '2.5GiB', '1e9' or '1000000' (K, M, G, T are powers of 1024)."""
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][0-9]+)?)\s*([kKmMgGtT]?)(?:i?[bB])?\s*", str(text))
    if not match:
        raise ValueError(f"cannot read '{text}' as a memory size (e.g. 8G, 512M, 2.5G)")
    value = float(match.group(1)) * _UNITS[match.group(2).upper()]
    if not (math.isfinite(value) and value >= 1):
        raise ValueError(f"memory size '{text}' must be at least one byte")
    return int(value)


def format_bytes(n: float) -> str:
    for unit, size in (("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{int(n)} bytes"


def physical_memory() -> int:
    """Bytes of RAM this process may use: the machine's, or its cgroup's limit when lower."""
    total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    try:
        text = _CGROUP_LIMIT.read_text().strip()
    except OSError:
        return total
    return min(total, int(text)) if text.isdigit() else total


@dataclass(frozen=True)
class MemoryBudget:
    """The most bytes input files may make the program allocate, and where that number came from."""

    limit: int
    origin: str  # e.g. "half of this machine's 23.5 GiB", "LANTERN_MEMORY_LIMIT=8G"

    @classmethod
    def from_settings(cls, option: Optional[str] = None,
                      environ: Mapping[str, str] = os.environ) -> "MemoryBudget":
        """--memory-limit if given, else LANTERN_MEMORY_LIMIT, else half of physical memory.
        A malformed setting is a ValueError naming the setting."""
        for name, text in ((OPTION, option), (ENVIRONMENT_VARIABLE, environ.get(ENVIRONMENT_VARIABLE))):
            if text:
                try:
                    return cls(parse_size(text), f"{name} {text}")
                except ValueError as error:
                    raise ValueError(f"{name}: {error}") from None
        total = physical_memory()
        return cls(int(total * DEFAULT_FRACTION), f"half of this machine's {format_bytes(total)}")

    def refusal(self, path: PathLike, what: str, needed: int, spent: int = 0) -> SceneError:
        already = f" on top of {format_bytes(spent)} already loaded" if spent else ""
        return SceneError(path, f"{what} needs {format_bytes(needed)}{already}, more than the memory "
                                f"limit of {format_bytes(self.limit)} ({self.origin}); raise it with "
                                f"{OPTION} SIZE or {ENVIRONMENT_VARIABLE}=SIZE")

    def check(self, path: PathLike, what: str, needed: int) -> None:
        """Refuse (SceneError) when `what` alone needs more than the budget."""
        if needed > self.limit:
            raise self.refusal(path, what, needed)


@dataclass
class MemoryLedger:
    """What the files of one scene have been charged so far against one budget."""

    budget: MemoryBudget
    spent: int = field(default=0)
    high_water: int = field(default=0)  # the most ever booked plus passing (what was allowed)

    def charge(self, path: PathLike, what: str, nbytes: int) -> None:
        """Book `nbytes` that stay allocated while the scene loads; refuse beyond the budget."""
        self.check_peak(path, what, nbytes)
        self.spent += int(nbytes)

    def check_peak(self, path: PathLike, what: str, nbytes: int) -> None:
        """Refuse a passing allocation (a decoder's scratch) that would not fit beside what is
        already booked; nothing is booked."""
        if self.spent + nbytes > self.budget.limit:
            raise self.budget.refusal(path, what, int(nbytes), self.spent)
        self.high_water = max(self.high_water, self.spent + int(nbytes))


# --- the film --------------------------------------------------------------------------------

# Bytes per pixel of a render: the film's fields (renderer/film/accumulation.py: mean and m2, 3 x f32 each;
# count, rejected and the adaptive-sampling state, i32 each), the renderer's work buffer (3 x f32),
# and the mean and variance images downloaded at the end (3 x f32 each). tests/scene/
# test_input_limits.py checks the film's share against a real Film. A render that keeps the
# denoising AOVs (renderer/film/aovs.py) adds their three fields (albedo, normal, sample count) and their
# two downloaded images. The
# fields are allocated in whole steps (renderer/runtime/allocation.py): the estimate counts the pixels
# allocated, a little more than the images' (at most a step's width of rows and columns).
FILM_FIELD_BYTES = 3 * 4 + 3 * 4 + 4 + 4 + 4
RENDER_BYTES_PER_PIXEL = FILM_FIELD_BYTES + 3 * 4 + 2 * 3 * 4
AOV_BYTES_PER_PIXEL = 2 * 3 * 4 + 4 + 2 * 3 * 4


def check_film(path: PathLike, width: int, height: int, budget: MemoryBudget, source: str,
               aovs: bool = False) -> None:
    """Refuse a film whose buffers would not fit the budget; `source` says where the size came
    from (e.g. "render.width x height", "--size"); `aovs`: the render keeps denoising AOVs."""
    per_pixel = RENDER_BYTES_PER_PIXEL + (AOV_BYTES_PER_PIXEL if aovs else 0)
    allocated_width, allocated_height = allocation_size(width, height)
    budget.check(path, f"a {width}x{height} film ({source}, {per_pixel} bytes per pixel)",
                 allocated_width * allocated_height * per_pixel)

"""Which chunk of a distributed render goes next: pure bookkeeping, no Ray and no Taichi.

The image's ROUND_SLICES pixel slices are cut into `groups` contiguous ranges. A chunk renders `spp`
samples of a run of slices of one group that all have the same number of samples, so every pixel it
covers takes exactly the samples it would take in one process (the sample index is the pixel's own
count). At most one chunk of a group is in flight: a group's next chunk continues from the state
the last one returned. Adaptive sampling's checks (renderer/film/adaptive.py) look at neighbouring
pixels of other groups, so no chunk passes a check point before every group has reached it and the
driver has run the check: the same check, on the same film, as one process runs.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from renderer.film.adaptive import next_check
from renderer.commands.distributed.pixel_groups import DONE
from renderer.film.pixel_slices import ROUND_SLICES

MAX_SPP = 2**31 - 1  # sample indices are 32-bit signed counts


@dataclass(frozen=True)
class Chunk:
    group: int
    first: int  # its slices: [first, first + count)
    count: int
    spp: int  # samples it adds to each of its pixels
    start: int  # samples its slices had before it


class ChunkPlanner:
    def __init__(self, progress: np.ndarray, groups: int, target: int | None, adaptive_min_spp: int | None = None):
        """`progress`: samples per slice so far (PixelSlices.progress); `target`: samples every
        slice ends with (None: a time budget, set by end_soon()); `adaptive_min_spp`: the
        adaptive sampling's first check point (None: uniform sampling)."""
        if ROUND_SLICES % groups:
            raise ValueError(f"{groups} groups do not divide {ROUND_SLICES} slices")
        self.progress = np.array(progress, dtype=np.int64)
        self.groups = groups
        self.size = ROUND_SLICES // groups
        self.target = target
        self.min_spp = adaptive_min_spp
        low = self.lowest()
        self.barrier = next_check(low, adaptive_min_spp) if adaptive_min_spp is not None and low != DONE else None
        self.in_flight: dict[int, Chunk] = {}
        self.stopped = False

    # --- state -----------------------------------------------------------------------------------
    def lowest(self, group: int | None = None) -> int:
        """Fewest samples of a slice still sampling (of one group, or of all); DONE if none is."""
        progress = self.progress if group is None else self.progress[group * self.size:(group + 1) * self.size]
        return int(progress.min())

    def limit(self) -> int:
        """No slice passes this many samples for now: the target, the next check point, MAX_SPP."""
        limit = MAX_SPP if self.target is None else self.target
        return limit if self.barrier is None else min(limit, self.barrier)

    def at_barrier(self) -> bool:
        """Every slice still sampling has reached the next check point: run the check now."""
        low = self.lowest()
        return (self.barrier is not None and not self.in_flight and low != DONE and low >= self.barrier
                and (self.target is None or self.barrier <= self.target))

    def finished(self) -> bool:
        if self.in_flight:
            return False
        low = self.lowest()
        return self.stopped or low == DONE or (self.target is not None and low >= self.target and not self.at_barrier())

    # --- decisions -------------------------------------------------------------------------------
    def next_chunk(self, spp: int) -> Chunk | None:
        """The next chunk of at most `spp` samples (None: nothing to hand out now). The group
        furthest behind goes first; within it the first run of slices furthest behind, up to the
        samples of the slices ahead of it, so that a group's slices come level."""
        if self.stopped:
            return None
        limit = self.limit()
        best, best_low = None, None
        for group in range(self.groups):
            low = self.lowest(group)
            if group in self.in_flight or low == DONE or low >= limit:
                continue
            if best is None or low < best_low:
                best, best_low = group, low
        if best is None:
            return None
        base = best * self.size
        progress = self.progress[base:base + self.size]
        first = int(np.argmax(progress == best_low))
        count = 1
        while first + count < self.size and progress[first + count] == best_low:
            count += 1
        ahead = progress[(progress > best_low) & (progress != DONE)]
        level = min(int(ahead.min()), limit) if ahead.size else limit
        chunk = Chunk(best, base + first, count, max(1, min(spp, level - best_low)), best_low)
        self.in_flight[best] = chunk
        return chunk

    def complete(self, chunk: Chunk) -> None:
        """`chunk`'s samples are in the film."""
        del self.in_flight[chunk.group]
        run = self.progress[chunk.first:chunk.first + chunk.count]
        run[run != DONE] += chunk.spp

    def abandon(self, chunk: Chunk) -> None:
        """`chunk` was lost (its worker died): it will be handed out again from the same state."""
        del self.in_flight[chunk.group]

    def passed_barrier(self, progress: np.ndarray) -> None:
        """The check has run: `progress` recomputed from the film (slices it stopped are DONE)."""
        self.progress = np.array(progress, dtype=np.int64)
        self.barrier = next_check(self.barrier, self.min_spp)

    def end_soon(self) -> None:
        """A time budget ran out: finish at the samples the furthest slice has or will have once
        the chunks in flight return, so the image ends with the same samples everywhere."""
        ends = [c.start + c.spp for c in self.in_flight.values()]
        active = self.progress[self.progress != DONE]
        self.target = int(max([*ends, *(active.tolist() if active.size else [0])]))

    def stop(self) -> None:
        """A stop request: hand out nothing more (the chunks in flight still return)."""
        self.stopped = True

    # --- reporting -------------------------------------------------------------------------------
    def samples_done(self) -> int:
        """Samples every pixel still sampling has."""
        low = self.lowest()
        if low != DONE:
            return low
        return int(self.target) if self.target is not None else 0

    def mean_spp(self) -> float:
        active = self.progress[self.progress != DONE]
        return float(active.mean()) if active.size else float(self.samples_done())


@dataclass
class ChunkSizer:
    """Samples per chunk: `fixed`, or about `seconds` of work at the rate measured so far. A worker's
    first chunk (it compiles) is one sample; a chunk grows at most `growth` times the last."""

    fixed: int | None = None
    seconds: float = 2.0
    growth: int = 4
    _seconds_per_slice_sample: float | None = None
    _last: int = 1

    def spp(self, slices: int, first_of_worker: bool, seconds_left: float | None = None) -> int:
        if self.fixed is not None:
            return self.fixed
        if first_of_worker or self._seconds_per_slice_sample is None:
            return 1
        per_sample = self._seconds_per_slice_sample * slices
        spp = min(self._last * self.growth, max(1, int(self.seconds / per_sample)))
        if seconds_left is not None:
            spp = min(spp, max(1, math.ceil(max(seconds_left, 0.0) / per_sample)))
        self._last = spp
        return spp

    def record(self, chunk: Chunk, seconds: float, first_of_worker: bool) -> None:
        """A chunk took `seconds` of rendering (its first, compiling chunk says nothing of the rate)."""
        if not first_of_worker:
            rate = seconds / (chunk.spp * chunk.count)
            previous = self._seconds_per_slice_sample
            self._seconds_per_slice_sample = rate if previous is None else 0.5 * (previous + rate)

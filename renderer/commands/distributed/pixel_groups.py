"""Which pixels a chunk of a distributed render covers, and their exact state in and out of a film.

A chunk renders a contiguous range of the ROUND_SLICES interleaved pixel slices
(renderer/film/pixel_slices.py): every range covers the whole image evenly, so chunks of equal size cost
about the same and the image has no seams between workers. A pixel's accumulation moves between the
driver and a worker as per-pixel arrays (the FilmState layers of those pixels), nothing else.
"""
from __future__ import annotations

import numpy as np

from renderer.film.adaptive import STOPPED
from renderer.film.accumulation import FilmState
from renderer.film.pixel_slices import ROUND_SLICES, rank_image

# A slice whose pixels all stopped (adaptive sampling) or that holds no pixel: nothing left to render.
DONE = np.iinfo(np.int64).max
PER_PIXEL = ("mean", "m2", "count", "rejected", "adaptive", "albedo", "normal", "aov_count")


class PixelSlices:
    """The pixels of each slice of a width x height image."""

    def __init__(self, width: int, height: int):
        self.width, self.height = width, height
        ranks = rank_image(width, height)  # [y, x], y up
        flat = ranks.ravel()
        self._order = np.argsort(flat, kind="stable").astype(np.int64)
        self._starts = np.searchsorted(flat[self._order], np.arange(ROUND_SLICES + 1))
        self._rank_of_row = ranks[::-1]  # as FilmState's rows (row 0 = top)

    def coords(self, first: int, count: int) -> tuple[np.ndarray, np.ndarray]:
        """(xs, ys), int32 film coordinates (y up), of the pixels of slices [first, first + count)."""
        flat = self._order[self._starts[first]:self._starts[first + count]]
        return (flat % self.width).astype(np.int32), (flat // self.width).astype(np.int32)

    def pixels(self, first: int, count: int) -> int:
        return int(self._starts[first + count] - self._starts[first])

    def gather(self, state: FilmState, first: int, count: int) -> dict[str, np.ndarray]:
        """The per-pixel arrays of slices [first, first + count) of `state` (its layers that exist)."""
        rows, columns = self._rows_columns(first, count)
        return {name: np.ascontiguousarray(getattr(state, name)[rows, columns]) for name in PER_PIXEL
                if getattr(state, name) is not None}

    def scatter(self, state: FilmState, first: int, count: int, arrays: dict[str, np.ndarray]) -> None:
        """Write per-pixel arrays of slices [first, first + count) into `state`."""
        rows, columns = self._rows_columns(first, count)
        for name, values in arrays.items():
            target = getattr(state, name)
            if target is not None:
                target[rows, columns] = values

    def progress(self, state: FilmState) -> np.ndarray:
        """Samples each slice has taken (int64 (ROUND_SLICES,)): the most any of its pixels still
        sampling has (a pixel's accepted plus rejected samples are its next sample index); DONE
        for a slice whose pixels all stopped or that has none."""
        samples = (state.count.astype(np.int64) + state.rejected).ravel()
        ranks = self._rank_of_row.ravel()
        if state.adaptive is not None:
            sampling = state.adaptive.ravel() != STOPPED
            samples, ranks = samples[sampling], ranks[sampling]
        progress = np.full(ROUND_SLICES, -1, np.int64)
        np.maximum.at(progress, ranks, samples)
        progress[progress < 0] = DONE
        return progress

    def _rows_columns(self, first: int, count: int) -> tuple[np.ndarray, np.ndarray]:
        xs, ys = self.coords(first, count)
        return self.height - 1 - ys, xs


def empty_state(width: int, height: int, adaptive: bool, aovs: bool) -> FilmState:
    """A film state with no samples, with the optional layers a render keeps."""
    zeros3 = lambda: np.zeros((height, width, 3), np.float32)  # noqa: E731
    return FilmState(zeros3(), zeros3(), np.zeros((height, width), np.int32), np.zeros((height, width), np.int32),
                     adaptive=np.zeros((height, width), np.int32) if adaptive else None,
                     albedo=zeros3() if aovs else None, normal=zeros3() if aovs else None,
                     aov_count=np.zeros((height, width), np.int32) if aovs else None)


def group_count(pixels: int, workers: int, min_group_pixels: int = 1024) -> int:
    """Pixel groups of a render: a power of two dividing ROUND_SLICES, at least four per worker so
    that the last chunks of a render leave few workers idle, but not so many that a group has fewer
    than `min_group_pixels` pixels (a launch over a few hundred pixels cannot use a CPU's threads)."""
    groups = 1
    while groups < 4 * workers and groups < ROUND_SLICES:
        groups *= 2
    while groups > 1 and pixels // groups < min_group_pixels:
        groups //= 2
    return groups

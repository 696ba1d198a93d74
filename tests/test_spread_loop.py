"""renderer/spread_loop.py: a spread loop takes each index once, and every contiguous share of its
iterations (what one CPU thread gets) samples the whole range."""
import numpy as np
import pytest
import taichi as ti

from renderer.spread_loop import SPREAD_BLOCKS, loop_index, loop_length, spread_run


@ti.kernel
def _visit(n: ti.i32, spread: ti.template(), taken: ti.types.ndarray(), order: ti.types.ndarray()):
    run = spread_run(n)
    for k in range(loop_length(n, run, spread)):
        i = loop_index(k, run, spread)
        order[k] = -1
        if i < n:
            ti.atomic_add(taken[i], 1)
            order[k] = i


def visit(n, spread=True):
    taken, order = np.zeros(max(n, 1), np.int32), np.full(n + 2 * SPREAD_BLOCKS, -2, np.int32)
    _visit(n, spread, taken, order)
    return taken[:n], order[order != -2]


@pytest.mark.parametrize("n", [0, 1, 63, 64, 65, 1000, 4096, 518_400, 2 * 960 + 7])
@pytest.mark.parametrize("spread", [True, False])
def test_every_index_is_taken_exactly_once(n, spread):
    taken, order = visit(n, spread)
    assert (taken == 1).all()
    assert sorted(order[order >= 0].tolist()) == list(range(n))
    assert len(order) < n + SPREAD_BLOCKS  # iterations past the indices: less than a run's worth each


@pytest.mark.parametrize("threads, n", [(2, 960), (2, 960 * 3), (4, 960 * 3 * 12), (16, 960 * 540)])
def test_each_threads_share_spans_the_range(threads, n):
    """A thread's contiguous share of the iterations takes equal numbers of indices from every
    1/threads of the range: a pass's dear and cheap pixels are shared out evenly (a row, a still
    frame's band of 3 rows, 12 bands, a whole 960x540 image)."""
    _, order = visit(n)
    share = len(order) // threads
    for t in range(threads):
        mine = order[t * share:(t + 1) * share]
        counts = np.bincount(mine[mine >= 0] * threads // n, minlength=threads)
        assert counts.max() - counts.min() <= 2 * spread_run_of(n), (t, counts)


def spread_run_of(n):
    return -(-n // SPREAD_BLOCKS)


def test_runs_stay_consecutive():
    _, order = visit(64 * 100)
    runs = order.reshape(SPREAD_BLOCKS, -1)
    assert (np.diff(runs, axis=1) == 1).all()

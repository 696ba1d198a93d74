"""The chunk planner and sizer of distributed renders: pure bookkeeping, no Ray."""
from itertools import takewhile

import numpy as np
import pytest

from renderer.film.adaptive import check_points
from renderer.commands.distributed.pixel_groups import DONE
from renderer.commands.distributed.planner import ChunkPlanner, ChunkSizer
from renderer.film.pixel_slices import ROUND_SLICES


def drain(planner, spp, order=None, on_chunk=None):
    """Hand out and complete chunks (completing them in `order`'s way: 'lifo' or 'fifo')."""
    handed = []
    while not planner.finished():
        chunk = planner.next_chunk(spp)
        if chunk is not None:
            handed.append(chunk)
            if on_chunk:
                on_chunk(chunk)
            continue
        if planner.at_barrier():
            planner.passed_barrier(planner.progress)
            continue
        pending = list(planner.in_flight.values())
        assert pending, "nothing in flight, nothing to hand out, not finished"
        planner.complete(pending[-1] if order == "lifo" else pending[0])
    return handed


@pytest.mark.parametrize("groups", [1, 4, 64])
@pytest.mark.parametrize("order", ["fifo", "lifo"])
def test_every_slice_gets_exactly_the_target(groups, order):
    planner = ChunkPlanner(np.zeros(ROUND_SLICES, np.int64), groups, target=13)
    chunks = drain(planner, spp=5, order=order)
    assert (planner.progress == 13).all()
    samples = np.zeros(ROUND_SLICES, int)
    for chunk in chunks:
        assert chunk.count >= 1 and chunk.spp >= 1
        assert chunk.first // planner.size == chunk.group  # a chunk stays in its group
        samples[chunk.first:chunk.first + chunk.count] += chunk.spp
    assert (samples == 13).all()


def test_chunks_continue_where_their_slices_stand():
    """Each chunk starts at the samples its slices have: no sample index is rendered twice."""
    planner = ChunkPlanner(np.zeros(ROUND_SLICES, np.int64), 8, target=9)
    seen = np.zeros(ROUND_SLICES, int)

    def check(chunk):
        assert (seen[chunk.first:chunk.first + chunk.count] == chunk.start).all()
        seen[chunk.first:chunk.first + chunk.count] += chunk.spp

    drain(planner, spp=4, order="lifo", on_chunk=check)
    assert (seen == 9).all()


def test_a_group_has_one_chunk_in_flight():
    planner = ChunkPlanner(np.zeros(ROUND_SLICES, np.int64), 2, target=100)
    a, b = planner.next_chunk(10), planner.next_chunk(10)
    assert {a.group, b.group} == {0, 1}
    assert planner.next_chunk(10) is None
    planner.complete(a)
    assert planner.next_chunk(10).group == a.group


def test_a_partial_round_is_levelled_first():
    """A one-process checkpoint stopped within a round: the slices behind catch up alone."""
    progress = np.full(ROUND_SLICES, 4, np.int64)
    progress[:100] = 5
    planner = ChunkPlanner(progress, 2, target=8)
    chunk = planner.next_chunk(16)
    assert (chunk.first, chunk.count, chunk.spp, chunk.start) == (100, 28, 1, 4)
    other = planner.next_chunk(16)
    assert (other.first, other.count, other.spp, other.start) == (128, 128, 4, 4)


def test_a_lost_chunk_is_handed_out_again_from_the_same_state():
    planner = ChunkPlanner(np.zeros(ROUND_SLICES, np.int64), 1, target=4)
    chunk = planner.next_chunk(4)
    planner.abandon(chunk)
    assert planner.next_chunk(4) == chunk


def test_no_chunk_passes_a_check_point_before_the_check():
    min_spp = 4
    planner = ChunkPlanner(np.zeros(ROUND_SLICES, np.int64), 4, target=40, adaptive_min_spp=min_spp)
    checks = []
    while not planner.finished():
        chunk = planner.next_chunk(7)
        if chunk is not None:
            assert chunk.start + chunk.spp <= planner.barrier
            planner.complete(chunk)
        elif planner.at_barrier():
            checks.append(int(planner.lowest()))
            progress = planner.progress.copy()
            if len(checks) == 2:
                progress[:64] = DONE  # the check stopped every pixel of a quarter of the slices
            planner.passed_barrier(progress)
    points = list(takewhile(lambda n: n <= 40, check_points(min_spp)))
    assert checks == points == [4, 8, 16, 32]
    assert (planner.progress[:64] == DONE).all() and (planner.progress[64:] == 40).all()


def test_a_time_budget_ends_level():
    planner = ChunkPlanner(np.zeros(ROUND_SLICES, np.int64), 4, target=None)
    a = planner.next_chunk(3)
    planner.complete(a)
    b = planner.next_chunk(3)
    c = planner.next_chunk(5)
    planner.end_soon()
    assert planner.target == max(b.start + b.spp, c.start + c.spp, a.spp)
    drain(planner, spp=8)
    assert (planner.progress == planner.target).all()


def test_a_stop_hands_out_nothing_more():
    planner = ChunkPlanner(np.zeros(ROUND_SLICES, np.int64), 4, target=10)
    chunk = planner.next_chunk(2)
    planner.stop()
    assert planner.next_chunk(2) is None and not planner.finished()
    planner.complete(chunk)
    assert planner.finished()


def test_empty_slices_are_done():
    progress = np.zeros(ROUND_SLICES, np.int64)
    progress[200:] = DONE
    planner = ChunkPlanner(progress, 1, target=2)
    drain(planner, spp=2)
    assert (planner.progress[:200] == 2).all() and planner.samples_done() == 2


def test_sizer_first_chunks_growth_and_budget():
    sizer = ChunkSizer(seconds=2.0)
    chunk = ChunkPlanner(np.zeros(ROUND_SLICES, np.int64), 1, 100).next_chunk(1)
    assert sizer.spp(256, first_of_worker=True) == 1
    sizer.record(chunk, 1.0, first_of_worker=True)  # compiling: says nothing of the rate
    assert sizer.spp(256, first_of_worker=False) == 1  # still no rate
    sizer.record(chunk, 0.01, first_of_worker=False)  # 0.01 s per sample of 256 slices
    assert sizer.spp(256, first_of_worker=False) == 4  # at most 4x the last chunk
    assert sizer.spp(256, first_of_worker=False) == 16
    assert sizer.spp(256, first_of_worker=False) == 64
    assert sizer.spp(256, first_of_worker=False) == 200  # 2 s at 0.01 s per sample
    assert sizer.spp(256, first_of_worker=False, seconds_left=0.05) == 5
    assert ChunkSizer(fixed=7).spp(256, first_of_worker=True) == 7


def test_chunks_lengthen_when_the_driver_link_would_saturate():
    from renderer.commands.distributed.render import DRIVER_BYTES_PER_SECOND, chunk_seconds

    assert chunk_seconds(2.0, 2, 500_000) == 2.0  # two local workers: far below the link
    # 100 workers each sending and receiving a 4K group's 1.17 MB: the link sets the chunk's length
    assert chunk_seconds(2.0, 100, 2 * 1_166_400) == pytest.approx(100 * 2 * 1_166_400 / DRIVER_BYTES_PER_SECOND)

"""The interactive benchmark's statistics (the benchmark itself drives a window: run it with
`python app.py bench interactive --quick`)."""
import random
import time
from types import SimpleNamespace

import pytest

from renderer.bench.interactive import (event_latencies, first_round, first_round_text, paired_rate_blocks,
                                        paired_rate_ratios, percentile, print_report)
from renderer.film.pixel_slices import ROUND_SLICES


def test_percentile_interpolates_between_order_statistics():
    values = [5.0, 1.0, 3.0, 2.0, 4.0]
    assert percentile(values, 0.0) == 1.0 and percentile(values, 1.0) == 5.0 and percentile(values, 0.5) == 3.0
    assert percentile(values, 0.95) == pytest.approx(4.0 + 0.8 * 1.0)  # position 0.95 * 4 = 3.8
    assert percentile([], 0.5) != percentile([], 0.5)  # NaN for no data


def test_an_event_waits_for_the_rest_of_its_frame_and_shows_at_the_end_of_the_next():
    """Frames of 40 ms: an event arriving at a uniform moment of one frame is seen after the rest
    of it plus the next, between 40 and 80 ms, 60 ms on average (the mean of 10,000 within 4
    standard errors: the rest of a frame is uniform, sd 40 / sqrt(12) ms)."""
    frames = [0.040] * 101
    latencies = event_latencies(frames, random.Random(7), count=10_000)
    assert len(latencies) == 10_000
    assert min(latencies) >= 0.040 and max(latencies) <= 0.080
    standard_error = 0.040 / 12 ** 0.5 / 10_000 ** 0.5
    assert abs(sum(latencies) / len(latencies) - 0.060) < 4 * standard_error


def test_a_long_frame_catches_events_in_proportion_to_its_length():
    """Frames of 40 ms, 1 s, 40 ms (events land in the first two, which have a next frame): one in
    the first (probability 0.04 / 1.04) waits for the long frame, >= 1 s; one in the long frame
    (1 / 1.04) waits >= 1 s only if it came in its first 40 ms (4%). So P(>= 1 s) = 0.08 / 1.04,
    against 0.52 if frames were hit equally often; 10,000 events, within 4 standard errors."""
    latencies = event_latencies([0.04, 1.0, 0.04], random.Random(1), count=10_000)
    assert 0.04 <= min(latencies) and max(latencies) <= 1.04 + 1e-12
    p = 0.08 / 1.04
    share = sum(v >= 1.0 for v in latencies) / len(latencies)
    assert abs(share - p) < 4 * (p * (1 - p) / len(latencies)) ** 0.5


def test_still_events_are_answered_by_the_frames_that_took_an_input():
    """Still frames of 40 ms that only render, and answering frames (render + present) of 50 ms:
    an event waits the rest of a 40 ms frame, then one answering frame: 50 to 90 ms."""
    latencies = event_latencies([0.040] * 30, random.Random(3), answers=[0.050, 0.050], count=5_000)
    assert len(latencies) == 5_000 and min(latencies) >= 0.050 and max(latencies) <= 0.090
    assert event_latencies([0.04], random.Random(3), answers=[]) == []
    assert event_latencies([0.04], random.Random(3)) == []  # no frame after it


def test_report_shows_each_switch_load_compile_and_first_image(capsys):
    still = {"samples_per_s": 2.5e5, "rate_ratio": 0.8, "frame_ms_median": 44.0}
    row = {"scene": "cornell_box", "integrator": "path", "latency_p50_ms": 70.0, "latency_p95_ms": 90.0,
           "whole_samples_p95_ms": 700.0, "still": still, "moving": {"frame_ms_median": 45.0}}
    compiled = dict(row, switch={"load_s": 0.5, "compile_s": 1.25, "first_image_s": 1.9})
    cached = dict(row, integrator="mis", switch={"load_s": 0.0, "compile_s": None, "first_image_s": 0.1})
    print_report([compiled, cached, {"scene": "pool", "integrator": "path", "skipped": "boom"}])
    rows = {tuple(line.split()[:2]): line.split() for line in capsys.readouterr().out.splitlines() if line.strip()}
    assert rows[("cornell_box", "path")][-3:] == ["0.50", "1.25", "1.90"]
    assert rows[("cornell_box", "mis")][-3:] == ["0.00", "-", "0.10"]
    assert "boom" in rows[("pool", "path")]


class _SlicedViewer:
    """Stands in for the viewer: each still frame renders `per_frame` pixel slices of a 16x16 film."""

    def __init__(self, per_frame: int, start: int = 0):
        self.per_frame = per_frame
        self.renderer = SimpleNamespace(slices_done=start, film=SimpleNamespace(width=16, height=16))
        self.session = SimpleNamespace(resolution=SimpleNamespace(min_still_slices=ROUND_SLICES))
        self.last_plan = None
        self.frames = 0
        self.presents = 0  # an untouched still view presents seldom; this one never
        self.resumed = []  # (kind of still frame set, clocks resumed) at each resume_still_clocks
        self._clock_reads = 0

    def still_clocks(self):
        self._clock_reads += 1
        return ("clocks", self._clock_reads)  # what the next resume of this kind must get back

    def resume_still_clocks(self, clocks=None):
        self.resumed.append((self.session.resolution.min_still_slices, clocks))

    def step(self, inp=None):
        assert self.session.resolution.min_still_slices == 1  # the viewer's own sliced frames
        self.renderer.slices_done += self.per_frame
        self.last_plan = SimpleNamespace(reset=False)
        self.frames += 1


def test_the_first_round_is_the_sliced_frames_until_its_last_slice():
    viewer = _SlicedViewer(per_frame=100)
    first = first_round(viewer)
    assert viewer.frames == 3  # 100, 200, 300: the third frame ends the round
    assert first["pixel_samples"] == 300 / ROUND_SLICES * 16 * 16
    assert first["samples_per_s"] == pytest.approx(first["pixel_samples"] / first["seconds"])
    # The frame that settled the switch already ended the round (a cheap view): nothing to measure,
    # which the table shows as "-" rather than a ratio of 0.
    done = _SlicedViewer(per_frame=100, start=ROUND_SLICES)
    assert first_round(done) is None and done.frames == 0
    assert first_round_text({"first_round": None}) == "-"


class _TimedStillViewer(_SlicedViewer):
    """A still view whose whole-sample frames take `whole_s` each and sliced frames `sliced_s`."""

    def __init__(self, whole_s: float, sliced_s: float):
        super().__init__(per_frame=1)
        self.seconds = {ROUND_SLICES: whole_s, 1: sliced_s}
        self.kinds = []

    def step(self, inp=None):
        fewest = self.session.resolution.min_still_slices
        self.kinds.append(fewest)
        time.sleep(self.seconds[fewest])
        self.renderer.slices_done += ROUND_SLICES if fewest == ROUND_SLICES else 1
        self.last_plan = SimpleNamespace(reset=False)
        self.frames += 1


def test_rate_blocks_pair_each_whole_block_with_sliced_frames_of_as_much_time():
    # A slow scene: one whole-sample frame (the least a block takes) outlasts the block's
    # seconds, and the sliced block after it lasts as long, not the nominal seconds.
    viewer = _TimedStillViewer(whole_s=0.02, sliced_s=0.002)
    blocks = paired_rate_blocks(viewer, seconds=0.01, rounds=2)
    assert [len(b["times"]) for b in blocks[ROUND_SLICES]] == [1, 1]
    # Several short frames fill the long one's time (how many depends on how long a 2 ms sleep
    # takes on a loaded machine: 10 when it is exact; the sums below are what the pairing promises).
    assert all(len(b["times"]) > 1 for b in blocks[1])
    for whole, sliced in zip(blocks[ROUND_SLICES], blocks[1]):
        assert sum(sliced["times"]) >= sum(whole["times"])
        assert sum(sliced["times"]) - sum(whole["times"]) <= max(sliced["times"])  # stops at the first frame past it
    # whole block, then its sliced block, in turn
    runs = [k for i, k in enumerate(viewer.kinds) if i == 0 or viewer.kinds[i - 1] != k]
    assert runs == [ROUND_SLICES, 1, ROUND_SLICES, 1]
    # each block resumes its own kind's clocks: the first of each kind with both due, the next
    # where the last block of that kind left them (read at its end), so each presents as a
    # continuous still view of its kind
    assert viewer.resumed == [(ROUND_SLICES, None), (1, None), (ROUND_SLICES, ("clocks", 1)), (1, ("clocks", 2))]
    assert blocks[1][0]["pixel_samples"] == len(blocks[1][0]["times"]) * 16 * 16 / ROUND_SLICES


def test_the_still_rate_is_the_median_of_the_pairs_ratios():
    def block(samples, *times):
        return {"pixel_samples": samples, "times": list(times), "presents": 0}
    blocks = {ROUND_SLICES: [block(100.0, 1.0), block(100.0, 0.5, 0.5), block(300.0, 2.0, 1.0)],
              1: [block(96.0, 0.5, 0.5), block(50.0, 1.0), block(291.0, 3.0)]}
    ratios = paired_rate_ratios(blocks)
    assert ratios == pytest.approx([0.96, 0.5, 0.97])  # the second pair disturbed: its median is 0.96

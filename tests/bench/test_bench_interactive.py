"""The interactive benchmark's statistics (the benchmark itself drives a window: run it with
`python app.py bench interactive --quick`)."""
import random

import pytest

from renderer.bench.interactive import event_latencies, percentile


def test_percentile_interpolates_between_order_statistics():
    values = [5.0, 1.0, 3.0, 2.0, 4.0]
    assert percentile(values, 0.0) == 1.0 and percentile(values, 1.0) == 5.0 and percentile(values, 0.5) == 3.0
    assert percentile(values, 0.95) == pytest.approx(4.0 + 0.8 * 1.0)  # position 0.95 * 4 = 3.8
    assert percentile([], 0.5) != percentile([], 0.5)  # NaN for no data


def test_an_event_waits_for_the_rest_of_its_frame_and_shows_at_the_end_of_the_next():
    """Frames of 40 ms: an event arriving at a uniform moment of one frame is seen after the rest
    of it plus the next, between 40 and 80 ms, 60 ms on average (the mean of 10,000 within 4
    standard errors: the rest of a frame is uniform, sd 40 / sqrt(12) ms)."""
    frames = [0.040] * 10_001
    latencies = event_latencies(frames, random.Random(7))
    assert len(latencies) == 10_000
    assert min(latencies) >= 0.040 and max(latencies) <= 0.080
    standard_error = 0.040 / 12 ** 0.5 / 10_000 ** 0.5
    assert abs(sum(latencies) / len(latencies) - 0.060) < 4 * standard_error
    # A long frame delays the events that arrive during it and those of the frame before.
    slow = event_latencies([0.04, 1.0, 0.04], random.Random(1))
    assert slow[0] >= 1.0 and slow[1] >= 0.04 and max(slow) <= 1.04

"""The interactive benchmark's statistics (the benchmark itself drives a window: run it with
`python app.py bench interactive --quick`)."""
import random

import pytest

from renderer.bench.interactive import event_latencies, percentile, print_report


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

"""The viewer's background denoiser: when it runs, that it never blocks, and which result shows."""
import threading

import numpy as np

from renderer.output.denoise import DenoiseInput
from viewer.denoise_worker import BackgroundDenoiser, wants_denoise


def test_denoise_at_the_first_sample_then_at_each_doubling():
    assert not wants_denoise(0.5, None)
    assert wants_denoise(1.0, None)
    assert not wants_denoise(1.9, 1.0) and wants_denoise(2.0, 1.0)
    assert not wants_denoise(7.0, 4.0) and wants_denoise(8.0, 4.0)


def source():
    return DenoiseInput(np.ones((4, 4, 3), np.float32))


def test_offer_returns_at_once_and_the_result_belongs_to_its_generation():
    release, finished = threading.Event(), threading.Event()

    def slow(s):
        release.wait(30.0)  # (a bound only so that a broken worker cannot hang the suite)
        finished.set()
        return s.color * 0.5

    worker = BackgroundDenoiser(slow)
    assert worker.offer(1, 1.0, source)
    # The caller (the window loop) does not wait: offer() returned while the job cannot have ended,
    # it waits for `release`, set only below. (An event, not a stopwatch: a busy machine may pause
    # this thread for any time, but cannot end the job.)
    assert not finished.is_set()
    assert worker.busy and not worker.offer(1, 4.0, source)  # one job at a time
    assert not finished.is_set()
    release.set()
    worker.wait()
    result = worker.result_for(1)
    assert result is not None and result.spp == 1.0 and np.allclose(result.image, 0.5)
    assert worker.result_for(2) is None  # a new accumulation does not show an old image


def test_the_input_is_taken_only_when_a_job_starts():
    taken = []
    worker = BackgroundDenoiser(lambda s: s.color)

    def take():
        taken.append(1)
        return source()

    assert not worker.offer(3, 0.25, take)  # below one sample: nothing downloaded
    assert worker.offer(3, 1.0, take)
    worker.wait()
    assert not worker.offer(3, 1.5, take) and worker.offer(3, 2.0, take)
    worker.wait()
    assert len(taken) == 2


def test_a_failure_is_one_line_and_keeps_the_viewer_running():
    def broken(s):
        raise RuntimeError("OIDN device creation failed\nmore detail")

    worker = BackgroundDenoiser(broken)
    assert worker.offer(1, 1.0, source)
    worker.wait()
    assert worker.error == "OIDN device creation failed" and worker.result_for(1) is None


def test_the_first_job_of_an_accumulation_may_use_the_quicker_denoiser():
    worker = BackgroundDenoiser(lambda s: s.color * 2.0, first=lambda s: s.color * 3.0)
    assert worker.offer(1, 1.0, source)
    worker.wait()
    first = worker.result_for(1)
    assert first.quick and np.allclose(first.image, 3.0)
    assert worker.offer(1, 2.0, source)
    worker.wait()
    second = worker.result_for(1)
    assert not second.quick and np.allclose(second.image, 2.0)
    assert worker.offer(2, 1.0, source)  # a new accumulation starts quick again
    worker.wait()
    assert worker.result_for(2).quick

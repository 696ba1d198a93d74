"""Distributed renders on a real local Ray (two CPUs, started by the module): exact merges, a killed
worker, a time budget, a stop and a resume, animation frames, and the errors a user meets."""
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import app
from renderer.camera import CameraFrame
from renderer.commands.distributed.cluster import RayCluster
from renderer.commands.distributed.render import DistributedOptions, DistributedRun, render_distributed
from renderer.commands.headless import RenderJob, Resume, render
from renderer.output.image_io import read_exr_layers
from renderer.scene.catalog import load_any, resolve_scene

ROOT = Path(__file__).resolve().parents[3]
SIZE = (64, 48)


@pytest.fixture(scope="module", autouse=True)
def local_ray():
    with RayCluster(cpus=2, address=None) as ray:
        yield ray


@pytest.fixture(scope="module")
def cornell():
    return load_any(resolve_scene("cornell_box"))


def job(**changes):
    settings = dict(spp=8, size=SIZE, integrator="mis", seed=5)
    settings.update(changes)
    return RenderJob(**settings)


def assert_same_film(a, b):
    for name in ("mean", "m2", "count", "rejected", "adaptive", "albedo", "normal"):
        x, y = getattr(a, name), getattr(b, name)
        assert (x is None) == (y is None), name
        if x is not None:
            assert np.array_equal(x, y), f"{name} differs (max {np.abs(x.astype(float) - y).max()})"


@pytest.fixture(scope="module")
def one_process(cornell):
    return render(cornell, job(spp=8))


def test_bit_identical_to_one_process_even_when_a_worker_is_killed(cornell, one_process):
    """Chunks of 3 spp over 8 (the last one short), split over two workers, one of which is killed
    during the third chunk: a new worker takes its place, the lost chunk is handed out again, and
    the merged film is the single process's, bit for bit."""
    handed = []

    def kill_the_third(chunk, pid):
        handed.append(chunk)
        if len(handed) == 3:
            os.kill(pid, signal.SIGKILL)

    run = DistributedRun()
    result = render_distributed(cornell, job(spp=8), DistributedOptions(workers=2, chunk_spp=3), run=run,
                                on_worker_started=kill_the_third)
    assert run.lost_chunks == 1 and len(run.worker_stats) == 3  # a third worker took the dead one's place
    assert handed.count(handed[2]) == 2  # the lost chunk was handed out again, unchanged
    assert run.chunks >= run.groups * -(-8 // 3)
    assert_same_film(result.state, one_process.state)
    assert np.array_equal(result.image, one_process.image)
    assert np.array_equal(result.variance, one_process.variance)
    assert result.spp == 8


def test_adaptive_sampling_and_aovs_are_bit_identical(cornell):
    wanted = job(spp=32, noise_threshold=0.1, min_spp=4, aovs=True)
    single = render(cornell, wanted)
    result = render_distributed(cornell, wanted, DistributedOptions(workers=2, chunk_spp=6))
    assert single.pixels_active < single.state.count.size  # some pixels stopped
    assert_same_film(result.state, single.state)
    assert result.pixels_active == single.pixels_active


def test_a_time_budget_ends_with_every_pixel_at_the_same_spp(cornell):
    result = render_distributed(cornell, job(spp=None, seconds=1.0), DistributedOptions(workers=2))
    samples = result.state.count + result.state.rejected
    assert result.spp >= 1 and (samples == result.spp).all()
    assert_same_film(result.state, render(cornell, job(spp=result.spp)).state)


class StopAfter:
    """A stop request that arrives once `chunks` chunks have been handed out."""

    def __init__(self, chunks):
        self.left = chunks

    def count(self, _chunk, _pid):
        self.left -= 1

    @property
    def requested(self):
        return self.left <= 0

    def defer(self):
        pass


def test_a_stopped_render_resumes_bit_identical(cornell, one_process):
    stop = StopAfter(3)
    first = render_distributed(cornell, job(spp=8), DistributedOptions(workers=2, chunk_spp=3), stop=stop,
                               on_worker_started=stop.count)
    assert first.interrupted and first.spp < 8
    resumed = render_distributed(cornell, job(spp=8), DistributedOptions(workers=1, chunk_spp=4),
                                 resume=Resume(first.state, first.spp, first.seconds_rendered))
    assert_same_film(resumed.state, one_process.state)


def test_a_checkpointed_distributed_render_continues_from_the_command_line(tmp_path, one_process):
    out, checkpoint = tmp_path / "c.exr", tmp_path / "c.ckpt"
    base = ["render", "cornell_box", "--size", "64x48", "--integrator", "mis", "--seed", "5", "--out", str(out),
            "--workers", "2", "--chunk-spp", "4"]
    assert app.main(base + ["--spp", "4", "--checkpoint", str(checkpoint)]) == 0
    # Continued distributed (the checkpoint says so), on one worker this time.
    assert app.main(["render", "--resume", str(checkpoint), "--spp", "8", "--chunk-spp", "2", "--workers", "1"]) == 0
    image = read_exr_layers(out)["RGB"]
    assert np.array_equal(image, one_process.image)


def test_animation_frames_on_workers_equal_local_frames(tmp_path):
    scene = ROOT / "tests" / "data" / "camera_path.toml"
    common = ["render", str(scene), "--frames", "0:2", "--fps", "2", "--spp", "2"]
    assert app.main(common + ["--out", str(tmp_path / "ray_#.exr"), "--workers", "2"]) == 0
    assert app.main(common + ["--out", str(tmp_path / "local_#.exr")]) == 0
    for frame in range(3):
        on_ray = read_exr_layers(tmp_path / f"ray_{frame}.exr")["RGB"]
        assert np.array_equal(on_ray, read_exr_layers(tmp_path / f"local_{frame}.exr")["RGB"])


def test_photon_mapping_is_refused_in_one_line(capsys):
    assert app.main(["render", "cornell_box", "--integrator", "sppm", "--workers", "2", "--spp", "1",
                     "--out", "/tmp/never.png"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == ("error: --workers: sppm renders whole-image photon passes and cannot be distributed; use "
                       "path, nee or mis")


def run_cli(*arguments, prelude=""):
    code = f"{prelude}import sys, app; sys.exit(app.main({list(arguments)!r}))"
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)


def lantern_lines(stderr: str) -> list[str]:
    """stderr without Taichi's own log lines ("[W 12/06/26 ...]", "[Taichi] ..."): Taichi may warn at
    exit that another process held the kernel cache's lock (the other test worker)."""
    return [line for line in stderr.strip().splitlines() if not re.match(r"\[(Taichi\]|[DIWE] \d)", line)]


def test_an_address_that_does_not_answer_is_one_line(tmp_path):
    done = run_cli("render", "cornell_box", "--spp", "1", "--ray-address", "127.0.0.1:9", "--out",
                   str(tmp_path / "x.png"))
    assert done.returncode == 2
    lines = lantern_lines(done.stderr)
    assert lines[-1].startswith("error: --ray-address 127.0.0.1:9: no Ray cluster answers there"), done.stderr


def test_without_ray_installed_it_says_so_in_one_line(tmp_path):
    done = run_cli("render", "cornell_box", "--spp", "1", "--workers", "2", "--out", str(tmp_path / "x.png"),
                   prelude="import sys; sys.modules['ray'] = None; ")
    assert done.returncode == 2
    assert lantern_lines(done.stderr)[-1] == ("error: distributed rendering needs Ray, which is not installed "
                                              "(pip install ray)"), done.stderr


def test_bench_scale_on_a_tiny_image(tmp_path):
    import json

    from renderer.bench import scale

    # (the full benchmark's other runs differ only in their worker count and chunk sizes)
    config = scale.ScaleBenchConfig(size=(48, 32), spp=3, distributed_runs=((2, 1),))
    assert scale.run(out_dir=tmp_path, config=config) == 0  # 0: every image bit-identical to one process
    report = json.loads((tmp_path / "bench_scale.json").read_text())
    runs = {r["name"]: r for r in report["runs"]}
    assert set(runs) == {"1 process x all cores", "2 workers x 1 thread, 1-spp chunks"}
    one_spp = runs["2 workers x 1 thread, 1-spp chunks"]
    assert one_spp["chunks"] == one_spp["groups"] * 3 and one_spp["bytes_per_chunk"] > 0
    assert report["chunk_rule"]["min_chunk_render_s"] > 0 and (tmp_path / "bench_scale.png").is_file()

"""The offline cache holds a whole session's kernels (renderer/runtime/arch.py): Taichi's default cap of
100 MB evicted kernels that scenes and test modules had compiled moments earlier."""
import os
import subprocess
import sys
from pathlib import Path

import taichi as ti

from renderer.runtime.arch import LANTERN_CACHE_FOLDER, OFFLINE_CACHE_MAX_BYTES, init_taichi


def test_the_suite_runtime_keeps_every_kernel_it_compiles():
    # the runtime conftest made for this module (the next test re-initialises it)
    config = ti.lang.impl.current_cfg()
    assert config.offline_cache
    assert config.offline_cache_max_size_of_files == OFFLINE_CACHE_MAX_BYTES > 100 * 1024**2
    assert config.offline_cache_file_path.endswith(LANTERN_CACHE_FOLDER)
    assert not config.make_cpu_multithreading_loop  # the tests schedule loops as the product does


def test_init_taichi_raises_the_cap_and_keeps_the_folder_asked_for(tmp_path):
    init_taichi("cpu", cache_dir=str(tmp_path))
    config = ti.lang.impl.current_cfg()
    assert config.offline_cache and config.offline_cache_max_size_of_files == OFFLINE_CACHE_MAX_BYTES
    assert config.offline_cache_file_path == str(tmp_path)


def test_kernels_compiled_under_lantern_loop_scheduling_have_a_folder_of_their_own(monkeypatch, tmp_path):
    # Taichi's cache key leaves the loop scheduling out: kernels compiled under its default (one
    # share of a loop per thread) must not be loaded under Lantern's dynamic sharing.
    monkeypatch.setenv("TI_OFFLINE_CACHE_FILE_PATH", str(tmp_path))
    init_taichi("cpu")
    config = ti.lang.impl.current_cfg()
    assert config.offline_cache_file_path == str(tmp_path / LANTERN_CACHE_FOLDER)
    assert not config.make_cpu_multithreading_loop  # threads take a loop's blocks as they finish


def test_a_cache_root_set_in_the_environment_starts_without_a_warning(tmp_path):
    """Taichi warns when a ti.init argument overrides its environment variable; Lantern's folder
    within the root the user set is no override of it (a new user saw the warning on every start)."""
    env = dict(os.environ, TI_OFFLINE_CACHE_FILE_PATH=str(tmp_path))
    code = ("import os; from renderer.runtime.arch import init_taichi; init_taichi('cpu'); "
            "print(os.environ['TI_OFFLINE_CACHE_FILE_PATH'])")
    done = subprocess.run([sys.executable, "-c", code], cwd=Path(__file__).resolve().parents[2], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "overridden" not in done.stderr + done.stdout and "[W " not in done.stderr, done.stderr
    assert done.stdout.strip().splitlines()[-1] == str(tmp_path)  # the variable is back for child processes

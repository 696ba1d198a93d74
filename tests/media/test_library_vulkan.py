"""The media and spectral Taichi funcs stay valid on a GPU back-end: one kernel calling all of them
(tests/media/library_kernel.py) runs on Vulkan (software lavapipe here) in a subprocess, since a
process holds one Taichi runtime, and must agree with the CPU up to f32 transcendental rounding."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.media.library_kernel import run
from tests.test_vulkan import vulkan_available

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.vulkan
def test_library_funcs_on_vulkan_match_cpu(tmp_path):
    if not vulkan_available():
        pytest.skip("no Vulkan driver (install libvulkan1 mesa-vulkan-drivers)")
    out = tmp_path / "vulkan.npy"
    proc = subprocess.run([sys.executable, "-m", "tests.media.library_kernel", "vulkan", str(out)], cwd=ROOT,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    gpu = np.load(out)
    cpu = run()
    assert np.isfinite(cpu).all() and np.isfinite(gpu).all()
    np.testing.assert_allclose(gpu, cpu, rtol=2e-4, atol=1e-5)

"""The wide BVHs on a GPU back-end: on Vulkan (software lavapipe here) the 4- and 8-wide traversals
(with scalar and with packet leaves) find the binary traversal's hits, and the Cornell box
rendered with the Renderer's default (8-wide, packet leaves) there equals the CPU's binary
traversal image by the suite's z-test.

Runs in subprocesses, since a process holds one Taichi runtime and the suite's is on the CPU.
"""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.geometry.test_wide_bvh import assert_same_hits
from tests.geometry.test_traversal import mixed_scene, random_rays
from tests.stats.image_tests import assert_agree
from tests.test_vulkan import vulkan_available

ROOT = Path(__file__).resolve().parents[2]

def run(out: Path, *args) -> dict:
    """tests/geometry/wide_bvh_vulkan_child.py in a process of its own; its arrays."""
    proc = subprocess.run([sys.executable, "-m", "tests.geometry.wide_bvh_vulkan_child", *map(str, args[:1]), str(out),
                           *map(str, args[1:])], capture_output=True, text=True, timeout=900, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return np.load(out)


@pytest.mark.vulkan
def test_wide_traversal_on_vulkan_finds_the_binary_hits(tmp_path):
    if not vulkan_available():
        pytest.skip("no Vulkan driver (install libvulkan1 mesa-vulkan-drivers)")
    got = run(tmp_path / "hits.npz", "hits")
    rng = np.random.default_rng(1)
    data, (_, d) = mixed_scene(rng), random_rays(rng, 4000)
    # a miss reads t = INF in both; compare as (t, 0, 0) rows (the barycentrics are not read back)
    kinds = ("stack", "wide4", "wide4+packets", "wide8", "wide8+packets")
    rows = {k: np.stack([got[k + "_t"], np.zeros(4000), np.zeros(4000)], axis=1) for k in kinds}
    for k in kinds[1:]:
        assert_same_hits((rows[k], got[k + "_prim"]), (rows["stack"], got["stack_prim"]), data, d, 2000)
        np.testing.assert_array_equal(got[k + "_shadow"], got["stack_shadow"])


@pytest.mark.vulkan
def test_cornell_box_on_vulkan_with_the_wide_traversal_equals_the_cpu_image(tmp_path):
    """The wide tree with packet leaves on Vulkan against the binary tree with scalar leaves on
    the CPU. Different seeds: the two images are independent estimates of the same expected
    image."""
    if not vulkan_available():
        pytest.skip("no Vulkan driver (install libvulkan1 mesa-vulkan-drivers)")
    vk = run(tmp_path / "vk.npz", "render", "vulkan", "wide8+packets", 1)  # the Renderer's default
    cpu = run(tmp_path / "cpu.npz", "render", "cpu", "stack", 2)
    assert vk["mean"].mean() > 0.01 and np.isfinite(vk["mean"]).all()
    assert_agree((vk["mean"], vk["var"]), (cpu["mean"], cpu["var"]), ("vulkan wide8", "cpu stack"))

"""The Sobol sampler on Vulkan in a process of its own (the suite's runtime is on the CPU):
`python -m tests.sampling.sobol_vulkan_child`. Exit 0: the same bits as the numpy model; 1: not;
3: no Vulkan device."""
import sys

import numpy as np


def main() -> int:
    from renderer.runtime.arch import init_taichi

    try:
        init_taichi("vulkan")
    except RuntimeError:
        return 3
    from renderer.sampling.sobol import SobolSampler, reference_get2d
    from tests.sampling.test_samplers import GET2D, draw

    got = draw(SobolSampler(), 16, 64, 1000, 0, 0xDEADBEEF, GET2D, 12345, 3, 2**20)
    ref = reference_get2d(np.arange(16)[:, None] * 3 + 12345, np.arange(64) + 2**20, 1000, 0xDEADBEEF)
    return 0 if np.array_equal(got, ref) else 1


if __name__ == "__main__":
    sys.exit(main())

"""Loop indices spread over the CPU's threads: a pass cut into SPREAD_BLOCKS runs of consecutive
indices, visited in bit-reversed order.

Taichi's CPU back-end splits a parallel loop's index range into one contiguous share per
thread, whatever `ti.loop_config(block_dim=...)` says (measured with Taichi 1.7.4 on 2 threads:
a loop of 2,048 items whose first 256 hold all the work ran no faster than on one thread, with
the default blocks and with blocks of 16; the same work spread over every 8th item ran 1.8x
faster). A pass's cost is not even along its pixels: the sky is cheap and the model dear, so
raster order gave one thread the sky and the other the model, and a still frame's pass of one
band of rows gave each thread half a row of very different cost. Cutting the pass into
SPREAD_BLOCKS runs and visiting them in bit-reversed order makes every contiguous share of the
loop (1/2, 1/4 ... 1/64 of it) a sample of the whole pass, while each run stays long (1/64 of
the pass: neighbouring pixels and memory; a still frame's pass of bands keeps most of each band
together).

    size = spread_run(n)
    for k in range(loop_length(n, size, spread)):
        i = loop_index(k, size, spread)
        if i < n:
            ...  # index i, each of [0, n) exactly once

Which index an iteration takes never changes what it computes, so images are bit-identical.
Measured with scripts/spread_loop_cost.py (figures in docs/architecture.md).

Only the CPU back-end spreads (`spreads_on_current_arch`): GPUs hand out blocks of a loop
dynamically and need no help, and on Vulkan (Taichi 1.7.4, lavapipe) a sample loop inside a
loop whose index came through `k % 64` lost iterations (a probe: `for s in range(5)` adding 1 to
a field ran twice), which the render kernel's Vulkan test caught.
"""
import taichi as ti

SPREAD_BITS = 6
SPREAD_BLOCKS = 1 << SPREAD_BITS  # runs a pass is cut into


@ti.func
def spread_run(n):
    """Indices per run of a spread loop over n indices (the last run may be short; 0 for n = 0,
    a loop of no iterations)."""
    return (n + SPREAD_BLOCKS - 1) // SPREAD_BLOCKS


@ti.func
def _reverse_block(j):
    reversed_j = 0
    for b in ti.static(range(SPREAD_BITS)):
        reversed_j |= ((j >> b) & 1) << (SPREAD_BITS - 1 - b)
    return reversed_j


@ti.func
def loop_length(n, run, spread: ti.template()):
    """Iterations of a loop over n indices: spread (SPREAD_BLOCKS runs of `run`) or plain."""
    length = n
    if ti.static(spread):
        length = SPREAD_BLOCKS * run
    return length


@ti.func
def loop_index(k, run, spread: ti.template()):
    """The index iteration k takes (>= n for the iterations past a short last run): spread, or k."""
    i = k
    if ti.static(spread):
        i = _reverse_block(k // run) * run + k % run
    return i


def spreads_on_current_arch() -> bool:
    """Whether loops should spread on the back-end Taichi runs on (the CPU's)."""
    return ti.lang.impl.current_cfg().arch in (ti.x64, ti.arm64)

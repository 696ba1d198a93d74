"""f32 boxes rounded outwards (renderer/geometry/box_rounding.py), shared by the BVH build and the
light tree: they contain the f64 boxes, by at most one f32 step, and keep f32 input exactly."""
import numpy as np

from renderer.geometry.box_rounding import round_out_f32


def test_f64_boxes_are_contained_within_one_step():
    rng = np.random.default_rng(5)
    lo = rng.normal(scale=100.0, size=(2000, 3))
    hi = lo + rng.uniform(0.0, 1.0, size=lo.shape)
    lo32, hi32 = round_out_f32(lo, hi)
    assert lo32.dtype == hi32.dtype == np.float32
    assert np.all(lo32.astype(np.float64) <= lo) and np.all(hi32.astype(np.float64) >= hi)
    # the nearest f32 on the right side: one step further would also contain, and is never taken
    assert np.all(np.nextafter(lo32, np.float32(np.inf)).astype(np.float64) > lo)
    assert np.all(np.nextafter(hi32, np.float32(-np.inf)).astype(np.float64) < hi)
    # most values are not f32 numbers: the rounding did move them
    assert np.mean(lo32.astype(np.float64) < lo) > 0.9 and np.mean(hi32.astype(np.float64) > hi) > 0.9


def test_f32_input_is_kept_exactly():
    lo = np.array([[0.1, -2.5, 3.0]], np.float32)
    hi = np.array([[0.2, -1.0, 7.5]], np.float32)
    lo32, hi32 = round_out_f32(lo, hi)
    np.testing.assert_array_equal(lo32, lo)
    np.testing.assert_array_equal(hi32, hi)


def test_f64_values_that_are_f32_numbers_stay():
    lo = np.array([[0.5, -0.25, 1024.0]])
    lo32, hi32 = round_out_f32(lo, lo + 1.0)
    np.testing.assert_array_equal(lo32, lo.astype(np.float32))
    np.testing.assert_array_equal(hi32, (lo + 1.0).astype(np.float32))

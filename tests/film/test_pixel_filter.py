"""The pixel filters' sampling (renderer/film/pixel_filter.py): for a test function h of the offset
from the pixel's centre, the mean of weight * h(offset) over samples must be integral(f h) /
integral(f), the filtered value (z-tests at the 1% level with Bonferroni's correction, fixed seed);
and the box filter draws the same jitter as before, weight 1."""
import numpy as np
import pytest
import taichi as ti
from scipy import integrate, stats

from renderer.film.filter_keys import filter_key
from renderer.film.pixel_filter import pixel_sample

N = 200_000
ALPHA = 0.01


@ti.kernel
def _draw(u: ti.types.ndarray(), out: ti.types.ndarray(), key: ti.template(), x: ti.i32, y: ti.i32, width: ti.i32,
          height: ti.i32):
    for i in range(u.shape[0]):
        position, weight = pixel_sample(ti.math.vec2(u[i, 0], u[i, 1]), x, y, width, height, key)
        out[i, 0] = position.x
        out[i, 1] = position.y
        out[i, 2] = weight


def draw(key, seed=1, pixel=(50, 50), size=(100, 100)):
    """Samples of pixel `pixel` of an image of `size` (by default far from its edges)."""
    u = np.random.default_rng(seed).uniform(0.0, 1.0, (N, 2)).astype(np.float32)
    out = np.zeros((N, 3), np.float32)
    _draw(u, out, key, *pixel, *size)
    return u, out[:, :2].astype(np.float64) - 0.5, out[:, 2].astype(np.float64)


def windowed_gaussian(s):
    r = 4 * s
    return lambda x: np.maximum(0.0, np.exp(-x * x / (2 * s * s)) - np.exp(-r * r / (2 * s * s))), r


TESTS = {  # test functions of (x, y): moments and a step the filter's tails decide
    "x^2": lambda x, y: x * x, "x^2 y^2": lambda x, y: x * x * y * y, "|x| > 0.5": lambda x, y: np.abs(x) > 0.5,
    "x > 0.2 and y < -0.1": lambda x, y: (x > 0.2) & (y < -0.1), "cos(3x + 2y)": lambda x, y: np.cos(3 * x + 2 * y),
}


@pytest.mark.parametrize("key, f, support", [
    (filter_key("tent", radius=1.5), lambda x: np.maximum(0.0, 1 - np.abs(x) / 1.5), 1.5),
    (filter_key("gaussian", stddev=0.5), *windowed_gaussian(0.5)),
    (filter_key("gaussian", stddev=0.3), *windowed_gaussian(0.3)),
])
def test_weighted_samples_estimate_the_filtered_value(key, f, support):
    _, offset, weight = draw(key)
    assert np.all(weight >= 0)
    # The tent lands inside its support; a Gaussian sample beyond the cut-off carries weight 0.
    inside = np.all(np.abs(offset) <= support * (1 + 1e-6), axis=1)
    assert inside.all() if key[0] == "tent" else np.all(weight[~inside] == 0)
    norm = integrate.quad(f, -support, support)[0] ** 2
    level = stats.norm.isf(ALPHA / 2 / len(TESTS))
    for name, h in TESTS.items():
        exact = integrate.dblquad(lambda y, x: f(x) * f(y) * h(x, y), -support, support, -support, support,
                                  epsabs=1e-10)[0] / norm
        values = weight * h(offset[:, 0], offset[:, 1])
        z = (values.mean() - exact) / (values.std(ddof=1) / np.sqrt(N))
        assert abs(z) < level, (key, name, values.mean(), exact, z)


def test_a_filter_ten_percent_too_wide_fails():
    """The check above has power: samples of a Gaussian of deviation 0.55 judged against 0.5."""
    f, support = windowed_gaussian(0.5)
    _, offset, weight = draw(filter_key("gaussian", stddev=0.55))
    h = TESTS["x^2"]
    exact = integrate.dblquad(lambda y, x: f(x) * f(y) * h(x, y), -support, support, -support, support)[0] / (
        integrate.quad(f, -support, support)[0] ** 2)
    values = weight * h(offset[:, 0], offset[:, 1])
    z = (values.mean() - exact) / (values.std(ddof=1) / np.sqrt(N))
    assert abs(z) > stats.norm.isf(ALPHA / 2 / len(TESTS))


@pytest.mark.parametrize("key, f, support", [
    (filter_key("tent", radius=1.5), lambda x: np.maximum(0.0, 1 - np.abs(x) / 1.5), 1.5),
    (filter_key("gaussian", stddev=0.5), *windowed_gaussian(0.5)),
])
@pytest.mark.parametrize("pixel, size", [((0, 1), (3, 40)), ((2, 0), (3, 1))])
def test_at_the_image_edges_the_filter_is_cut_and_renormalised(key, f, support, pixel, size):
    """As Mitsuba's film: a pixel near an edge averages the filter over the image only."""
    _, offset, weight = draw(key, pixel=pixel, size=size)
    lo = [-(pixel[i] + 0.5) for i in (0, 1)]  # the image's edges from the pixel's centre
    hi = [size[i] - pixel[i] - 0.5 for i in (0, 1)]
    inside = (offset[:, 0] >= lo[0]) & (offset[:, 0] <= hi[0]) & (offset[:, 1] >= lo[1]) & (offset[:, 1] <= hi[1])
    assert np.all(weight[~inside] == 0)
    axes = [(max(lo[i], -support), min(hi[i], support)) for i in (0, 1)]
    norm = integrate.quad(f, *axes[0])[0] * integrate.quad(f, *axes[1])[0]
    level = stats.norm.isf(ALPHA / 2 / 2)
    for name in ("x^2", "x > 0.2 and y < -0.1"):
        h = TESTS[name]
        exact = integrate.dblquad(lambda y, x: f(x) * f(y) * h(x, y), *axes[0], *axes[1], epsabs=1e-10)[0] / norm
        values = weight * h(offset[:, 0], offset[:, 1])
        z = (values.mean() - exact) / (values.std(ddof=1) / np.sqrt(N))
        assert abs(z) < level, (key[0], pixel, size, name, values.mean(), exact, z)


def test_the_box_draws_the_jitter_as_it_was():
    u, offset, weight = draw(filter_key("box"))
    np.testing.assert_array_equal(offset + 0.5, u.astype(np.float64))
    assert np.all(weight == 1.0)


def test_unknown_filters_are_refused():
    with pytest.raises(ValueError, match="unknown pixel filter 'mitchell'"):
        filter_key("mitchell")

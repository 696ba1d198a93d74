"""The tabulated-CDF search (renderer/sampling/cdf.py) that environment-map sampling and photon
emission share, against numpy's searchsorted, on 1-d and 2-d tables with zero-width intervals."""
import numpy as np
import taichi as ti

from renderer.sampling.cdf import cdf_interval


def _table(weights):
    c = np.concatenate([[0.0], np.cumsum(weights)]) / np.sum(weights)
    c[-1] = 1.0
    return c.astype(np.float32)


@ti.kernel
def _search_1d(cdf: ti.template(), count: ti.i32, us: ti.types.ndarray(), out: ti.types.ndarray()):
    for k in range(us.shape[0]):
        out[k] = cdf_interval(cdf, 0, count, us[k])


@ti.kernel
def _search_2d(cdf: ti.template(), row: ti.i32, count: ti.i32, us: ti.types.ndarray(), out: ti.types.ndarray()):
    for k in range(us.shape[0]):
        out[k] = cdf_interval(cdf, row, count, us[k])


def _expected(cdf, us):
    """The largest k with cdf[k] <= u, among the count = len(cdf) - 1 intervals."""
    return np.minimum(np.searchsorted(cdf, us, side="right") - 1, len(cdf) - 2)


def test_1d_matches_searchsorted_and_skips_empty_intervals():
    weights = np.array([0.0, 3.0, 0.0, 0.0, 1.0, 2.0, 0.0, 5.0, 0.0])
    table = _table(weights)
    cdf = ti.field(ti.f32, shape=table.shape[0])
    cdf.from_numpy(table)
    edges = table[table < 1.0]  # u on every interval's start (u is in [0, 1))
    us = np.concatenate([np.linspace(0.0, 0.99999994, 997), edges]).astype(np.float32)
    out = np.zeros(us.shape[0], np.int32)
    _search_1d(cdf, len(weights), us, out)
    np.testing.assert_array_equal(out, _expected(table, us))
    assert set(np.unique(out)) == set(np.flatnonzero(weights > 0))  # no empty interval chosen


def test_2d_searches_the_given_row():
    rows = [np.array([1.0, 0.0, 1.0, 2.0]), np.array([0.0, 0.0, 4.0, 1.0]), np.array([5.0, 1.0, 0.0, 0.0])]
    tables = np.stack([_table(w) for w in rows])
    cdf = ti.field(ti.f32, shape=tables.shape)
    cdf.from_numpy(tables)
    us = np.linspace(0.0, 0.99999994, 501).astype(np.float32)
    for r, table in enumerate(tables):
        out = np.zeros(us.shape[0], np.int32)
        _search_2d(cdf, r, tables.shape[1] - 1, us, out)
        np.testing.assert_array_equal(out, _expected(table, us), err_msg=f"row {r}")

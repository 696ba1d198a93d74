"""Inverting a tabulated CDF on the device: the binary search that environment-map sampling
(rows, then texels within a row) and photon emission (emitters by power) share."""
import taichi as ti


@ti.func
def cdf_interval(cdf: ti.template(), row, count, u):
    """The largest k in [0, count) with cdf[k] <= u (cdf[row, k] for a 2-d table, one CDF per
    row): the interval [cdf[k], cdf[k + 1]) that holds u. cdf[0] must be 0 and u >= 0, so
    intervals of width zero are never chosen."""
    lo = 0
    hi = count
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        below = False
        if ti.static(len(cdf.shape) == 2):
            below = cdf[row, mid] <= u
        else:
            below = cdf[mid] <= u
        if below:
            lo = mid
        else:
            hi = mid
    return lo

"""Benchmarks behind "what accuracy costs in time": each prints a table and writes JSON + plots."""


def _sdf(**kw):
    from renderer.bench.sdf import run

    return run(**kw)


def _startup(**kw):
    from renderer.bench.startup import run

    return run(**kw)


def _bvh(**kw):
    from renderer.bench.bvh import run

    return run(**kw)


def _integrators(**kw):
    from renderer.bench.integrators import run

    return run(**kw)


def _features(**kw):
    from renderer.bench.features import run

    return run(**kw)


def _photons(**kw):
    from renderer.bench.photons import run

    return run(**kw)


BENCHMARKS = {"sdf": _sdf, "startup": _startup, "bvh": _bvh, "integrators": _integrators, "features": _features,
              "photons": _photons}

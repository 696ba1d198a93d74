"""Helpers shared by the benchmarks: timing, image error, JSON reports, plots and tables.

Nothing here touches Taichi at import time; the benchmarks initialise it themselves.

Image error follows Rousselle et al. ("Adaptive rendering with non-local means filtering", 2012):
relative MSE is mean((x - ref)^2 / (ref^2 + eps)) with eps = 1e-2, taken over pixels and channels,
so dark regions do not dominate and bright ones do not vanish.
"""
from __future__ import annotations

import json
import math
import os
import platform
import shlex
import statistics
import sys
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Callable, Iterable, Sequence

import numpy as np

from renderer.output.atomic_write import atomic_output, write_text_atomic

REL_MSE_EPS = 1e-2


# --- timing --------------------------------------------------------------------------------------

@dataclass
class Timing:
    """Wall-clock seconds of `runs` timed calls after `warmup` untimed ones."""

    times: list[float]
    warmup_times: list[float] = field(default_factory=list)

    @property
    def median(self) -> float:
        return statistics.median(self.times)

    @property
    def min(self) -> float:
        """The fastest run: on a busy machine, the least disturbed one."""
        return min(self.times)

    @property
    def spread(self) -> float:
        """(max - min) / median of the timed runs: a rough stability indicator."""
        return (max(self.times) - min(self.times)) / self.median if self.median > 0 else 0.0

    def as_dict(self) -> dict:
        return {"median_s": self.median, "min_s": self.min, "times_s": list(self.times), "warmup_s": list(self.warmup_times),
                "spread": self.spread}


def time_call(fn: Callable[[], object], runs: int = 3, warmup: int = 1,
              clock: Callable[[], float] = time.perf_counter) -> Timing:
    """Call `fn` `warmup` times untimed (compilation, caches), then `runs` times timed.

    `fn` must itself wait for any asynchronous device work it starts (e.g. end with ti.sync()).
    """
    if runs < 1:
        raise ValueError("runs must be at least 1")
    warm = []
    for _ in range(warmup):
        t0 = clock()
        fn()
        warm.append(clock() - t0)
    times = []
    for _ in range(runs):
        t0 = clock()
        fn()
        times.append(clock() - t0)
    return Timing(times, warm)


# --- image error ---------------------------------------------------------------------------------

def _pair(image, reference) -> tuple[np.ndarray, np.ndarray]:
    x = np.asarray(image, np.float64)
    r = np.asarray(reference, np.float64)
    if x.shape != r.shape:
        raise ValueError(f"image shape {x.shape} differs from reference shape {r.shape}")
    return x, r


def mse(image, reference) -> float:
    x, r = _pair(image, reference)
    return float(np.mean((x - r) ** 2))


def rmse(image, reference) -> float:
    return math.sqrt(mse(image, reference))


def rel_mse_map(image, reference, eps: float = REL_MSE_EPS) -> np.ndarray:
    """Per-element (x - ref)^2 / (ref^2 + eps)."""
    x, r = _pair(image, reference)
    return (x - r) ** 2 / (r * r + eps)


def rel_mse(image, reference, eps: float = REL_MSE_EPS) -> float:
    return float(np.mean(rel_mse_map(image, reference, eps)))


def _per_pixel(values: np.ndarray) -> np.ndarray:
    """Average the channel axis of an (H, W, C) map; leave (H, W) maps alone."""
    return values.mean(axis=-1) if values.ndim == 3 else values


def _top_mask(values: np.ndarray, trim: float) -> np.ndarray:
    """True for the ceil(trim * n) largest entries of `values` (ties broken by position)."""
    flat = values.ravel()
    k = int(math.ceil(trim * flat.size)) if trim > 0 else 0
    mask = np.zeros(flat.size, bool)
    if k > 0:
        mask[np.argpartition(flat, flat.size - k)[flat.size - k:]] = True
    return mask.reshape(values.shape)


def rel_mse_trimmed(image, reference, trim: float = 1e-3, eps: float = REL_MSE_EPS) -> float:
    """relMSE without the `trim` fraction of pixels with the largest error (fireflies): rare
    high-energy samples otherwise decide the comparison of two low-spp images on their own."""
    per_pixel = _per_pixel(rel_mse_map(image, reference, eps))
    return float(per_pixel[~_top_mask(per_pixel, trim)].mean())


@dataclass
class ErrorDifference:
    """metric(a) - metric(b) for two renderings of the same scene against one reference.

    The standard error comes from the per-pixel differences of the squared errors: pixels are
    sampled independently, so SE = std(d_pixel) / sqrt(pixels). When a and b share random numbers
    (same seed) the pairing cancels most of the Monte Carlo noise and the test is sharp. With
    `trim` > 0, pixels among the `trim` fraction of largest errors of either image are left out
    of both (the pairing is kept).
    """

    metric: str
    a: float
    b: float
    difference: float
    standard_error: float
    trim: float = 0.0

    @property
    def z(self) -> float:
        if self.standard_error > 0:
            return self.difference / self.standard_error
        return 0.0 if self.difference == 0 else math.copysign(math.inf, self.difference)

    @property
    def relative(self) -> float:
        """difference / b (0 when b is 0)."""
        return self.difference / self.b if self.b else 0.0

    def as_dict(self) -> dict:
        return {"metric": self.metric, "trim": self.trim, "a": self.a, "b": self.b, "difference": self.difference,
                "relative_difference": self.relative, "standard_error": self.standard_error, "z": self.z}


def error_difference(image_a, image_b, reference, metric: str = "rel_mse", trim: float = 0.0) -> ErrorDifference:
    if metric == "rel_mse":
        ea = _per_pixel(rel_mse_map(image_a, reference))
        eb = _per_pixel(rel_mse_map(image_b, reference))
    elif metric == "mse":
        xa, r = _pair(image_a, reference)
        xb, _ = _pair(image_b, reference)
        ea, eb = _per_pixel((xa - r) ** 2), _per_pixel((xb - r) ** 2)
    else:
        raise ValueError(f"unknown metric '{metric}' (rel_mse or mse)")
    keep = ~(_top_mask(ea, trim) | _top_mask(eb, trim))
    ea, eb = ea[keep], eb[keep]
    d = ea - eb
    se = float(np.std(d, ddof=1) / math.sqrt(d.size)) if d.size > 1 else math.inf
    return ErrorDifference(metric, float(ea.mean()), float(eb.mean()), float(d.mean()), se, trim)


Z_SIGNIFICANT = 1.96  # two-sided 5% level of a paired comparison (error_difference's z)


def paired_verdict(paired: dict | None) -> str:
    """'better' / 'worse' where image a's error (ErrorDifference.as_dict()) differs from image b's
    at the 5% level, else 'tie'; 'n/a' without a comparison."""
    if not paired:
        return "n/a"
    if paired["z"] < -Z_SIGNIFICANT:
        return "better"
    return "worse" if paired["z"] > Z_SIGNIFICANT else "tie"


def paired_text(paired: dict | None) -> str:
    """z of the comparison and its verdict, e.g. '-3.1 better' ('n/a' without one)."""
    return f"{paired['z']:+.1f} {paired_verdict(paired)}" if paired else "n/a"


def image_errors(image, reference, trim: float = 1e-3) -> dict:
    return {"rmse": rmse(image, reference), "rel_mse": rel_mse(image, reference),
            "rel_mse_trimmed": rel_mse_trimmed(image, reference, trim)}


# --- reports -------------------------------------------------------------------------------------

def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return value


def write_json(path: Path, data: dict) -> Path:
    path = Path(path)
    write_text_atomic(path, json.dumps(_jsonable(data), indent=2) + "\n")
    return path


def speed_runtime() -> str:
    """Taichi on the CPU with every kernel optimisation (these benchmarks measure speed), unless
    the caller (a test session) has initialised it already; returns the back-end's name."""
    import taichi as ti

    from renderer.runtime.arch import init_taichi

    if not ti.lang.impl.get_runtime().prog:
        init_taichi("cpu", optimize="run")
    return str(ti.lang.impl.current_cfg().arch).split(".")[-1]


def load_average() -> list[float] | None:
    """1, 5 and 15 minute load averages: timings are only as quiet as the machine."""
    try:
        return [round(v, 2) for v in os.getloadavg()]
    except OSError:
        return None


def machine_info() -> dict:
    info = {"python": sys.version.split()[0], "platform": platform.platform(), "cpus": os.cpu_count(),
            "processor": platform.processor() or platform.machine(), "load_average": load_average()}
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    info["processor"] = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        from importlib.metadata import version

        info["taichi"] = version("taichi")
    except Exception:  # noqa: BLE001 - informational only
        pass
    return info


def report_header(benchmark: str, quick: bool, load_before: list[float] | None, **fields) -> dict:
    """The opening entries of every benchmark's JSON report: which benchmark, when (UTC), the
    command line that ran it, the machine, then the benchmark's own `fields` (its configuration,
    back-end, ...) and the load averages before the run and now: timings are only as quiet as
    the machine."""
    return {"benchmark": benchmark, "quick": quick,
            "date": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            "command": shlex.join([Path(sys.executable).name, *sys.argv]), "machine": machine_info(), **fields,
            "load_average": {"before": load_before, "after": load_average()}}


def pyplot():
    """matplotlib.pyplot on the Agg back-end (no display needed)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path: Path) -> Path:
    path = Path(path)
    fig.tight_layout()
    with atomic_output(path) as temporary:
        fig.savefig(temporary, dpi=110, format=path.suffix.lstrip(".") or None)
    pyplot().close(fig)
    return path


# --- tables --------------------------------------------------------------------------------------

def format_table(headers: Sequence[str], rows: Iterable[Sequence[object]], title: str | None = None) -> str:
    """A plain aligned text table; numbers right-aligned, text left-aligned."""
    cells = [[str(h) for h in headers]] + [[_cell(v) for v in row] for row in rows]
    numeric = [all(_is_number(r[i]) for r in cells[1:]) if len(cells) > 1 else False for i in range(len(headers))]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]

    def line(row):
        return "  ".join(c.rjust(w) if numeric[i] else c.ljust(w) for i, (c, w) in enumerate(zip(row, widths))).rstrip()

    out = []
    if title:
        out.append(title)
    out.append(line(cells[0]))
    out.append("  ".join("-" * w for w in widths))
    out.extend(line(r) for r in cells[1:])
    return "\n".join(out)


def print_table(headers, rows, title: str | None = None) -> None:
    print(format_table(headers, rows, title), flush=True)
    print(flush=True)


def _is_number(text: str) -> bool:
    try:
        float(text.rstrip("%x").replace("+", "", 1))
        return True
    except ValueError:
        return False


def _cell(value) -> str:
    if isinstance(value, float):
        if not math.isfinite(value):
            return str(value)
        if value == 0:
            return "0"
        magnitude = abs(value)
        if magnitude >= 1000 or magnitude < 1e-3:
            return f"{value:.3g}"
        if magnitude >= 100:
            return f"{value:.1f}"
        if magnitude >= 10:
            return f"{value:.2f}"
        return f"{value:.3f}"
    return str(value)


def verdict(ok: bool) -> str:
    return "PASS" if ok else "FAIL"


def time_interleaved(calls: dict, runs: int = 3, warmup: int = 1,
                     clock: Callable[[], float] = time.perf_counter, after: Callable | None = None) -> dict:
    """Time several calls round-robin (a, b, c, a, b, c, ...) so slow drifts of the machine
    (other processes, clock changes) spread over all of them instead of biasing one.

    Returns {name: Timing}. Each call is warmed up `warmup` times first. `after(name)`, if given,
    runs untimed after each timed call (e.g. to read back a result).
    """
    if runs < 1:
        raise ValueError("runs must be at least 1")
    warm = {name: [] for name in calls}
    times = {name: [] for name in calls}
    for name, fn in calls.items():
        for _ in range(warmup):
            t0 = clock()
            fn()
            warm[name].append(clock() - t0)
    for _ in range(runs):
        for name, fn in calls.items():
            t0 = clock()
            fn()
            times[name].append(clock() - t0)
            if after is not None:
                after(name)
    return {name: Timing(times[name], warm[name]) for name in calls}


STARTED = time.perf_counter()  # when the benchmarks were imported: the clock of log()'s lines


def log(message: str) -> None:
    """A progress line on stderr, stamped with the seconds since the benchmarks were imported."""
    print(f"{time.perf_counter() - STARTED:6.1f} s  {message}", file=sys.stderr, flush=True)


def describe_error(error: BaseException) -> str:
    """One line for a report: the exception's type and the last line of its message."""
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[-1] if text else ''}"[:300]


def load_named_scene(name: str):
    """A catalog scene name, a scene file or a model file, loaded."""
    from renderer.scene.catalog import load_any, resolve_scene

    return load_any(resolve_scene(name))


REPO_ROOT = Path(__file__).resolve().parents[2]


def run_module(module: str, args: Sequence[str], timeout: float):
    """`python -m module args` in a fresh process, from the repository root with the repository
    importable (benchmarks that must measure a cold interpreter or runtime run their work so)."""
    import subprocess

    env = dict(os.environ)
    env["PYTHONPATH"] = str(REPO_ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return subprocess.run([sys.executable, "-m", module, *args], cwd=REPO_ROOT, env=env, capture_output=True,
                          text=True, timeout=timeout)


def child_report(stdout: str, stderr: str, returncode: int, marker: str) -> tuple[dict | None, str]:
    """The JSON a child printed after its last `marker`, or (None, why there is none)."""
    lines = [line for line in stdout.splitlines() if line.startswith(marker)]
    if not lines:
        tail = " | ".join(stderr.strip().splitlines()[-3:])
        return None, f"child exited with {returncode} and no report: {tail}"
    return json.loads(lines[-1][len(marker):]), ""


def dir_bytes(path) -> int:
    """Total size of the files below `path`."""
    return sum(f.stat().st_size for f in Path(path).rglob("*") if f.is_file())

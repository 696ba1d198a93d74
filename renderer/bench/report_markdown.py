"""Markdown pieces of the benchmark page (renderer/bench/report.py): numbers, tables, folds.

Report values come from JSON written by common.write_json, so a number may also be None (NaN) or
the strings "inf" / "-inf"; every formatter here takes those as they are.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Iterable, Sequence

MISSING = "–"
_NUMERIC_TEXT = re.compile(r"^[-+]?(\d|∞)")  # a cell written as a figure ("1.23x", "25.0 %", "-∞")


@dataclass
class Section:
    """What the page shows of one benchmark's report besides its header and plots: one or two
    sentences on what its knobs cost (computed from the figures), then Markdown blocks (tables
    with their captions, folds)."""

    findings: list[str] = field(default_factory=list)
    blocks: list[str] = field(default_factory=list)


def is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def num(value, digits: int = 3) -> str:
    """A figure to `digits` significant digits; integers in full, with thousands separators."""
    if value is None:
        return MISSING
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return f"{value:,}"
    if isinstance(value, float):
        if not math.isfinite(value):
            return MISSING if math.isnan(value) else ("∞" if value > 0 else "-∞")
        if value == 0:
            return "0"
        if 1e-3 <= abs(value) < 1e5:
            text = f"{value:.{digits}g}"
            return f"{float(text):,.0f}" if "e" in text else text
        mantissa, exponent = f"{value:.{max(digits - 1, 0)}e}".split("e")
        return f"{mantissa}e{int(exponent)}"
    if value in ("inf", "-inf"):
        return "∞" if value == "inf" else "-∞"
    return str(value)


def pct(value, digits: int = 1, signed: bool = False) -> str:
    """A fraction as a percentage (0.25 -> 25.0 %)."""
    if not is_number(value) or not math.isfinite(value):
        return MISSING
    return f"{100 * value + 0.0:{'+' if signed else ''}.{digits}f} %"  # + 0.0: no "-0.0 %"


def times(value, digits: int = 2) -> str:
    """A ratio as a factor (1.234 -> 1.23x)."""
    if not is_number(value) or not math.isfinite(value):
        return MISSING
    if abs(value) >= 10:  # three significant digits or so: 12.3x, 1,289x
        return f"{value:,.{1 if abs(value) < 100 else 0}f}x"
    return f"{value:.{digits}f}x"


def seconds(value) -> str:
    return MISSING if not is_number(value) else f"{num(value)} s"


def interval(ratio: dict | None) -> str:
    """A median with its 95 % interval: {'median', 'lo', 'hi'} -> '1.012 [0.998, 1.025]'."""
    if not ratio or not all(is_number(ratio.get(k)) for k in ("median", "lo", "hi")):
        return MISSING
    return f"{ratio['median']:.3f} [{ratio['lo']:.3f}, {ratio['hi']:.3f}]"


def verdict(passed) -> str:
    return MISSING if passed is None else ("PASS" if passed else "FAIL")


def _cell(value) -> str:
    text = value if isinstance(value, str) else num(value)
    return text.replace("|", "\\|").replace("\n", " ")


def table(headers: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    """A Markdown table; numeric cells (anything but str) formatted by num() and right-aligned."""
    rows = [list(r) for r in rows]
    right = [bool(rows) and all(not isinstance(r[i], str) or r[i] == MISSING or _NUMERIC_TEXT.match(r[i])
                                for r in rows) for i in range(len(headers))]
    lines = ["| " + " | ".join(_cell(h) for h in headers) + " |",
             "|" + "".join(" ---: |" if r else " --- |" for r in right)]
    lines += ["| " + " | ".join(_cell(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def details(summary: str, body: str) -> str:
    """A folded block (GitHub renders <details>); the blank lines let Markdown inside it render."""
    return f"<details><summary>{summary}</summary>\n\n{body}\n\n</details>"


def listing(items: Sequence[str]) -> str:
    """'a', 'a and b', 'a, b and c'."""
    items = list(items)
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def spread(values: Sequence[float], fmt=num) -> str:
    """'a' for one value or equal values, else 'lo–hi'."""
    values = [v for v in values if is_number(v) and math.isfinite(v)]
    if not values:
        return MISSING
    lo, hi = fmt(min(values)), fmt(max(values))
    return lo if lo == hi else f"{lo}–{hi}"

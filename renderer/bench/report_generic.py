"""The benchmark page's section for a report it has no dedicated section for (a new benchmark):
its top-level records as plain tables, so its figures show before anyone writes the summary."""
from __future__ import annotations

from renderer.bench.report_markdown import Section, details, is_number, table

# The header every report opens with (common.report_header), its plot list and run bookkeeping:
# shown elsewhere on the page or not figures at all.
HEADER_KEYS = frozenset({"benchmark", "quick", "date", "command", "machine", "load_average", "config", "notes",
                         "plots", "plot", "total_seconds"})
MAX_COLUMNS = 10
FOLD_ROWS = 12  # longer tables are folded


def _scalar(value) -> bool:
    return value is None or isinstance(value, (str, bool)) or is_number(value)


def _records_table(records: list[dict]) -> str:
    """The columns every record holds as a plain value (the first MAX_COLUMNS of them)."""
    columns = [k for k in records[0] if all(k in r and _scalar(r[k]) for r in records)][:MAX_COLUMNS]
    if not columns:
        return ""
    return table(columns, [[r[k] for k in columns] for r in records])


def generic_section(report: dict) -> Section:
    section = Section()
    for key, value in report.items():
        if key in HEADER_KEYS:
            continue
        text = ""
        if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            text, rows = _records_table(value), len(value)
        elif isinstance(value, dict) and value and all(_scalar(v) for v in value.values()):
            text, rows = table(["", "value"], [[k, v] for k, v in value.items()]), len(value)
        if text:
            section.blocks.append(details(f"`{key}` ({rows} rows)", text) if rows > FOLD_ROWS
                                  else f"`{key}`:\n\n{text}")
    return section

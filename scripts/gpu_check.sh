#!/usr/bin/env bash
# Every catalog scene on CUDA and on the CPU at 320x180: compile and render times, the speed-up,
# and a z-test of the two images (scripts/gpu_check.py; a few minutes). Without a CUDA device it
# prints "skipped: no CUDA device" and exits 0.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-.venv/bin/python}
[ -x "$PY" ] || PY=python3
exec "$PY" -m scripts.gpu_check "$@"

#!/usr/bin/env bash
# The test command of the README: sets up (idempotent) and runs the whole suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# Two workers (the machine's two cores), whole files per worker so module fixtures are shared.
exec .venv/bin/python -m pytest tests -n 2 --dist loadfile "$@"

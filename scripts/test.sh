#!/usr/bin/env bash
# The test command of the README: sets up (idempotent) and runs the suite.
#   bash scripts/test.sh           the default run (what CI runs): every test but the full tier's
#   bash scripts/test.sh --full    every test (the full tier: tests/conftest.py FULL_TIER, marked slow)
# Other arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
tier=(-m "not slow")
if [[ "${1:-}" == "--full" ]]; then
    tier=()
    shift
fi
# Two workers (the machine's two cores), whole files per worker so module fixtures are shared. A
# worker that crashes ends the run with its test named: a replaced worker once left the run hanging.
exec .venv/bin/python -m pytest tests -n 2 --dist loadfile --max-worker-restart 0 "${tier[@]}" "$@"

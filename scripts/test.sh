#!/usr/bin/env bash
# Set up (if needed) and run the test suite. Extra arguments go to pytest.
#   scripts/test.sh            lint (ruff) + fast and physics tests (what CI runs)
#   scripts/test.sh --slow     also the slow checks (marker "slow")
# Test files run on GENDEX_TEST_WORKERS processes (default 2, CI's cores; 0: all in this process), each file's
# tests on one of them so module fixtures (an env, a solved scene) are built once.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/scripts/setup.sh"
cd "$ROOT"
args=()
marker="not slow and not gpu"
for a in "$@"; do
  if [ "$a" = "--slow" ]; then marker="not gpu"; else args+=("$a"); fi
done
"$ROOT/.venv/bin/ruff" check "$ROOT"
exec "$ROOT/.venv/bin/python" -m pytest -m "$marker" -n "${GENDEX_TEST_WORKERS:-2}" --dist loadfile "${args[@]}"

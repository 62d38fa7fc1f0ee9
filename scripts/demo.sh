#!/usr/bin/env bash
# Set up (if needed) and run GenDex's main job on its embedded defaults; extra arguments go to `gendex demo`.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/scripts/setup.sh"
cd "$ROOT"
exec "$ROOT/.venv/bin/gendex" demo "$@"

#!/usr/bin/env bash
# GenDex set-up: idempotent, safe to run on every invocation.
#   1. a virtual environment in .venv (Python 3.11) with torch==2.13.0 installed first (CPU build),
#      then the project and its pinned dependencies (constraints.txt);
#   2. a working Vulkan device for SAPIEN: when none is found and this is Debian 12, Mesa >= 23 lavapipe
#      from bookworm-backports is installed. The apt source is derived from the machine's own apt config;
#   3. Debian's chromium and chromium-driver, for the leaderboard's browser test (as root, when missing).
# Re-runs are fast: a stamp records the hash of the files that define the environment.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${GENDEX_VENV:-$ROOT/.venv}"
PY="${GENDEX_PYTHON:-python3.11}"
command -v "$PY" >/dev/null 2>&1 || PY=python3
STAMP="$VENV/.gendex-setup-stamp"
log() { echo "[gendex setup] $*" >&2; }

want_hash() {
  cat "$ROOT/pyproject.toml" "$ROOT/constraints.txt" "$ROOT/scripts/setup.sh" | sha256sum | cut -d' ' -f1
}

install_python_env() {
  if [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$(want_hash)" ]; then
    return 0
  fi
  local ver
  ver="$("$PY" -c 'import sys; print("%d.%d" % sys.version_info[:2])')"
  if [ "$ver" != "3.11" ]; then
    log "Python 3.11 is required (found $ver at $(command -v "$PY")); set GENDEX_PYTHON to a 3.11 interpreter"
    exit 2
  fi
  [ -x "$VENV/bin/python" ] || { log "creating venv $VENV"; "$PY" -m venv "$VENV"; }
  # torch first: the pinned CPU build; anything installed later that depends on torch then reuses it.
  "$VENV/bin/python" -m pip install -q --upgrade "pip>=24" wheel
  log "installing torch==2.13.0 (CPU)"
  "$VENV/bin/python" -m pip install -q "torch==2.13.0"
  log "installing gendex and pinned dependencies"
  "$VENV/bin/python" -m pip install -q -c "$ROOT/constraints.txt" -e "$ROOT[dev,stats,ray]"
  want_hash > "$STAMP"
}

vulkan_ok() {
  # SAPIEN is the judge: it must find a device that has every feature it needs.
  "$VENV/bin/python" - <<'PYEOF' >/dev/null 2>&1
import sapien
sapien.render.RenderSystem()
PYEOF
}

install_lavapipe() {
  if [ "$(id -u)" != "0" ]; then
    log "no working Vulkan device and not root: install Mesa >= 23 (mesa-vulkan-drivers) or an NVIDIA driver"
    exit 3
  fi
  . /etc/os-release
  if [ "${VERSION_CODENAME:-}" != "bookworm" ]; then
    log "no working Vulkan device; automatic install only supports Debian 12 (found ${PRETTY_NAME:-unknown})"
    exit 3
  fi
  local src=/etc/apt/sources.list.d/debian.sources
  local bpo=/etc/apt/sources.list.d/gendex-bookworm-backports.sources
  if [ ! -f "$bpo" ]; then
    [ -f "$src" ] || { log "cannot find $src to derive a backports source from"; exit 3; }
    # Copy the stanza that carries the 'bookworm' suite (the main archive), switch its suite to backports.
    awk 'BEGIN{RS=""; ORS="\n\n"} /Suites:[^\n]*bookworm([ \n]|$)/ && !/bookworm-security/ {print; exit}' "$src" \
      | sed -E 's/^Suites:.*/Suites: bookworm-backports/' > "$bpo.tmp"
    grep -q '^Suites: bookworm-backports' "$bpo.tmp" || { rm -f "$bpo.tmp"; log "no bookworm stanza in $src"; exit 3; }
    mv "$bpo.tmp" "$bpo"
    log "added apt source $bpo (derived from $src)"
  fi
  log "installing Mesa lavapipe from bookworm-backports"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq -t bookworm-backports mesa-vulkan-drivers >/dev/null
}

install_browser() {
  # Debian's Chromium and its driver, for the leaderboard's browser test (tests/web/); nothing is downloaded by the
  # test itself. Only as root on Debian; elsewhere the test skips and says why.
  command -v chromium >/dev/null 2>&1 && command -v chromedriver >/dev/null 2>&1 && return 0
  if [ "$(id -u)" != "0" ] || ! command -v apt-get >/dev/null 2>&1; then
    log "chromium + chromium-driver missing and not installable here (not root or no apt): the browser test skips"
    return 0
  fi
  log "installing chromium and chromium-driver (Debian) for the leaderboard's browser test"
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >/dev/null \
    || { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver \
         >/dev/null; } || log "could not install chromium: the browser test skips"
}

install_python_env
install_browser
if ! vulkan_ok; then
  install_lavapipe
  vulkan_ok || { log "Vulkan still unusable after installing lavapipe"; exit 3; }
fi
log "ready: $VENV"

#!/usr/bin/env bash
# A side virtual environment with lerobot 0.4.4, for checking that GenDex datasets load in lerobot itself.
# lerobot cannot live in the project venv: its releases need Python 3.12, or (0.4.4) a torch older than ours, and
# PyPI's torchvision does not import beside torch 2.13.0+cpu; torch 2.14.1 + torchvision 0.29.1 is the pair that
# does (about 5.5 GB). Idempotent: a stamp records what was installed. Prints the venv's python on success.
#   bash scripts/lerobot_venv.sh            # -> .venv-lerobot/bin/python
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${GENDEX_LEROBOT_VENV:-$ROOT/.venv-lerobot}"
PY="${GENDEX_PYTHON:-python3.11}"
command -v "$PY" >/dev/null 2>&1 || PY=python3
PKGS=("datasets<5" "huggingface-hub<1" "av" "draccus==0.10.0" "accelerate" "jsonlines" "deepdiff" "einops" "pandas"
      "pyarrow" "opencv-python-headless" "imageio[ffmpeg]" "gymnasium" "packaging" "termcolor"
      "diffusers" "pyserial"   # imported by lerobot.policies (its GR00T and robot modules) when a config is loaded
      "torchcodec")            # lerobot 0.4.4's video decoder (torchvision 0.29 has no VideoReader any more)
WANT="torch==2.14.1 torchvision==0.29.1 lerobot==0.4.4 ${PKGS[*]}"
STAMP="$VENV/.gendex-lerobot-stamp"
log() { echo "[lerobot venv] $*" >&2; }
if [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$WANT" ]; then
  echo "$VENV/bin/python"; exit 0
fi
if ! ldconfig -p 2>/dev/null | grep -q libavcodec.so; then  # torchcodec loads the system's FFmpeg libraries
  if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    log "installing FFmpeg's shared libraries (Debian) for torchcodec"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libavcodec59 libavformat59 libavutil57 libswscale6 \
      libswresample4 libavfilter8 libavdevice59 >/dev/null
  else
    log "FFmpeg's shared libraries are missing (libavcodec): lerobot will not decode videos"
  fi
fi
[ -x "$VENV/bin/python" ] || { log "creating $VENV"; "$PY" -m venv "$VENV"; }
"$VENV/bin/python" -m pip install -q --upgrade "pip>=24" wheel
log "installing torch 2.14.1 + torchvision 0.29.1"
"$VENV/bin/python" -m pip install -q "torch==2.14.1" "torchvision==0.29.1"
log "installing lerobot 0.4.4 (without its pins) and what it imports"
"$VENV/bin/python" -m pip install -q --no-deps "lerobot==0.4.4"
"$VENV/bin/python" -m pip install -q "${PKGS[@]}"
echo "$WANT" > "$STAMP"
echo "$VENV/bin/python"

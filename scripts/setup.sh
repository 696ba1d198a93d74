#!/usr/bin/env bash
# Installs what Lantern needs on a Debian machine with Python 3.10/3.11:
#  - Debian: the Vulkan loader and software driver (for the window and the Vulkan test), Xvfb and
#    xdotool (for the end-to-end viewer test), when missing and when apt-get can be used;
#  - Python: a virtual environment in .venv with the project and its test extras.
# Safe to run again; it only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

PY=${PYTHON:-python3}
need_apt=()
for pkg in libvulkan1 mesa-vulkan-drivers xvfb xdotool; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need_apt+=("$pkg")
done
if [ ${#need_apt[@]} -gt 0 ]; then
  if command -v apt-get >/dev/null 2>&1 && { [ "$(id -u)" = 0 ] || command -v sudo >/dev/null 2>&1; }; then
    SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
    echo "setup: installing Debian packages: ${need_apt[*]}"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need_apt[@]}" >/dev/null
  else
    echo "setup: cannot install ${need_apt[*]} (no apt-get or no root): the window, the Vulkan test and" \
         "the end-to-end viewer test will be skipped; headless CPU rendering still works." >&2
  fi
fi

if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip >/dev/null
.venv/bin/python -m pip install -q -e ".[test]"
echo "setup: ready (.venv)"

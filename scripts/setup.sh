#!/usr/bin/env bash
# Installs what Lantern needs on a Debian machine with Python 3.10/3.11:
#  - Debian: the Vulkan loader and software driver (for the window and the Vulkan test), Xvfb,
#    xdotool and ImageMagick (the end-to-end viewer test drives the window with xdotool and grabs
#    the screen with ImageMagick's `import`), and libllvm19 (the libLLVM of Mitsuba's LLVM
#    variants, renderer/bench/mitsuba_side.py), when missing and when apt-get can be used;
#  - Python: a virtual environment in .venv with the project and its test extras (which bring
#    embreex and mitsuba for the benchmarks' tests).
# Safe to run again; it only installs what is missing. A failing apt-get (no network, a lock held
# by another apt) only skips the Debian packages, with a note of what that costs: the Python
# environment is created either way, and headless CPU rendering needs nothing from apt.
set -euo pipefail
cd "$(dirname "$0")/.."

PY=${PYTHON:-python3}
APT_LOCK_WAIT=${APT_LOCK_WAIT:-60}  # seconds to wait for another apt to release its lock

skipped() {  # the packages not installed, and which tests will be skipped without them
  local uses=()
  case " $* " in *" libvulkan1 "*|*" mesa-vulkan-drivers "*) uses+=("the window and the Vulkan test");; esac
  case " $* " in *" xvfb "*|*" xdotool "*|*" imagemagick "*) uses+=("the end-to-end viewer test");; esac
  case " $* " in *" libllvm19 "*) uses+=("Mitsuba's LLVM variants (Mitsuba then renders on its slow scalar one)");; esac
  local IFS=";"
  echo "setup: skipped installing $* (without them: ${uses[*]} will be skipped);" \
       "headless CPU rendering still works." >&2
}

install_debian_packages() {
  local need=()
  for pkg in libvulkan1 mesa-vulkan-drivers xvfb xdotool imagemagick libllvm19; do
    dpkg -s "$pkg" >/dev/null 2>&1 || need+=("$pkg")
  done
  [ ${#need[@]} -eq 0 ] && return 0
  if ! command -v apt-get >/dev/null 2>&1; then
    echo "setup: no apt-get on this machine." >&2; skipped "${need[*]}"; return 0
  fi
  local sudo=""
  if [ "$(id -u)" != 0 ]; then
    if command -v sudo >/dev/null 2>&1; then sudo="sudo"; else
      echo "setup: not root and no sudo." >&2; skipped "${need[*]}"; return 0
    fi
  fi
  local apt=($sudo env DEBIAN_FRONTEND=noninteractive apt-get -o "DPkg::Lock::Timeout=$APT_LOCK_WAIT" -qq)
  echo "setup: installing Debian packages: ${need[*]}"
  local log
  log=$(mktemp)
  if ! "${apt[@]}" update >"$log" 2>&1; then
    echo "setup: apt-get failed: $(grep -E '^(E|W):' "$log" | head -n 2 | tr '\n' ' ')" >&2
    skipped "${need[*]}"; rm -f "$log"; return 0
  fi
  # libllvm19 in a call of its own: a release without it (it is Debian 12's) must not cost the others.
  local main=() llvm=() group
  for pkg in "${need[@]}"; do
    if [ "$pkg" = libllvm19 ]; then llvm+=("$pkg"); else main+=("$pkg"); fi
  done
  for group in "${main[*]}" "${llvm[*]}"; do
    [ -n "$group" ] || continue
    # shellcheck disable=SC2086  # (package names, split on purpose)
    if ! "${apt[@]}" install -y $group >"$log" 2>&1; then
      echo "setup: apt-get failed: $(grep -E '^(E|W):' "$log" | head -n 2 | tr '\n' ' ')" >&2
      skipped "$group"
    fi
  done
  rm -f "$log"
}

install_debian_packages

if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip >/dev/null
.venv/bin/python -m pip install -q -e ".[test]"
# Byte-compile the project's own modules, as pip does for the packages it installs: the editable
# install runs them from source, and where PYTHONDONTWRITEBYTECODE is set (or the checkout is
# read-only) every command would otherwise compile ~120 modules again (about 0.3 s of each start).
# Python checks each .pyc against its source's time stamp, so an edited module is compiled afresh.
.venv/bin/python -m compileall -q app.py renderer viewer shaders_sdf scripts >/dev/null
echo "setup: ready (.venv)"

#!/usr/bin/env bash
# Create .venv and install everything TreeSketch needs (idempotent).
# Debian packages (libllvm19 for mitsuba's fast LLVM backend) are installed when missing
# and we are root; without them the renderer falls back to mitsuba's scalar backend.
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${PYTHON:-python3}"

if ! ls /usr/lib/x86_64-linux-gnu/libLLVM-19.so* /usr/lib/*/libLLVM.so.19* >/dev/null 2>&1; then
    if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
        echo "setup: installing Debian package libllvm19 (mitsuba's LLVM backend)"
        (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libllvm19) \
            || echo "setup: WARNING: could not install libllvm19; rendering will use scalar_rgb"
    else
        echo "setup: libllvm19 missing and not root; rendering will use scalar_rgb"
    fi
fi

# The service's browser tests drive Debian's chromium through Playwright (never
# `playwright install`, which downloads a browser build); the page's three.js comes from npm.
apt_install() {  # apt_install WHAT PACKAGE...: install when root, else say what is missing
    local what="$1"; shift
    if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
        echo "setup: installing Debian package(s) $* ($what)"
        (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$@") \
            || echo "setup: WARNING: could not install $*"
    else
        echo "setup: $* missing and not root ($what)"
    fi
}
if [ ! -x /usr/bin/chromium ]; then
    apt_install "headless browser for the web page tests" chromium
fi
if ! command -v npm >/dev/null 2>&1; then
    apt_install "the web page's three.js" npm
fi
# the Blender add-on's headless test (make test runs it) and `make blender-test`
if ! command -v blender >/dev/null 2>&1 || ! dpkg -s python3-numpy >/dev/null 2>&1; then
    apt_install "Blender 3.4 for the add-on's test" blender python3-numpy
fi
if command -v npm >/dev/null 2>&1 && [ ! -f treesketch/service/static/node_modules/three/build/three.module.js ]; then
    echo "setup: installing three.js for the web page (npm ci)"
    (cd treesketch/service/static && npm ci --no-audit --no-fund --loglevel=error)
fi

if [ ! -x .venv/bin/python ]; then
    "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
# torch first, pinned: pip takes the CPU build of torch 2.13.0 that lies on this disk.
.venv/bin/python -m pip install -q "torch==2.13.0"
.venv/bin/python -m pip install -q -e ".[dev,cluster]"
touch .venv/.installed
echo "setup: done ($(.venv/bin/python --version))"

#!/usr/bin/env bash
# Installs what Plumbline needs beyond the Rust toolchain. Safe to run more than once.
set -euo pipefail
rustup component add rustfmt clippy >/dev/null 2>&1 || true
# socat makes the virtual serial port pair for the lidar record tests (issue 5).
if ! command -v socat >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1; then
  (apt-get update -qq && apt-get install -y -qq socat) >/dev/null 2>&1 \
    || echo "setup: could not install socat; the lidar serial-port tests will skip" >&2
fi
# The real-client tests' Python packages (pymavlink as the ground station) live in .venv at the
# repository root, made from scripts/requirements-test.txt; Debian's python needs python3-venv.
root="$(cd "$(dirname "$0")/.." && pwd)"
if ! python3 -c 'import venv, ensurepip' >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1; then
  (apt-get update -qq && apt-get install -y -qq python3-venv) >/dev/null 2>&1 \
    || echo "setup: could not install python3-venv" >&2
fi
if [ ! -x "$root/.venv/bin/python" ]; then
  python3 -m venv "$root/.venv"
fi
"$root/.venv/bin/python" -m pip install -q --disable-pip-version-check \
  -r "$root/scripts/requirements-test.txt"
# Headless Chromium for the web view's browser tests (Playwright in .venv drives it; no browser
# download).
if ! command -v chromium >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1; then
  (apt-get update -qq && apt-get install -y -qq chromium) >/dev/null 2>&1 \
    || echo "setup: could not install chromium; the web view tests will fail" >&2
fi

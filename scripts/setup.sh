#!/usr/bin/env bash
# Installs what Plumbline needs beyond the Rust toolchain. Safe to run more than once.
set -euo pipefail
rustup component add rustfmt clippy >/dev/null 2>&1 || true
# socat makes the virtual serial port pair for the lidar record tests (issue 5).
if ! command -v socat >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1; then
  (apt-get update -qq && apt-get install -y -qq socat) >/dev/null 2>&1 \
    || echo "setup: could not install socat; the lidar serial-port tests will skip" >&2
fi

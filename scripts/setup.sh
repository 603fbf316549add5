#!/usr/bin/env bash
# Installs what Plumbline needs beyond the Rust toolchain. Safe to run more than once.
set -euo pipefail
rustup component add rustfmt clippy >/dev/null 2>&1 || true

#!/usr/bin/env bash
# The onboard stack's golden replay (crates/core/tests/golden_replay.rs).
#   bash scripts/golden.sh outputs   # after an intended change of onboard behaviour: rewrite the
#                                    # expected outputs, and commit them with the change
#   bash scripts/golden.sh inputs    # record a new input flight from the simulator, then the outputs
set -euo pipefail
cd "$(dirname "$0")/.."
dir=crates/core/tests/golden
case "${1:-}" in
  inputs)
    cargo build --release -q -p plumbline
    out=$(mktemp -d)
    args="sim --world room --scenario hold --lidar xv11 --controller pid --duration 3 --seed 2"
    target/release/plumbline $args --out "$out" >/dev/null
    python3 scripts/golden_inputs.py "$out" "plumbline $args" > "$dir/inputs.txt"
    rm -r "$out"
    ;&
  outputs)
    PLUMBLINE_BLESS_GOLDEN=1 cargo test -q -p plumbline-core --test golden_replay
    git diff --stat -- "$dir" || true
    ;;
  *)
    echo "usage: bash scripts/golden.sh outputs|inputs" >&2
    exit 2
    ;;
esac

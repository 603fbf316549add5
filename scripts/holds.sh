#!/usr/bin/env bash
# 60 s closed-loop holds in the simulated room, one TSV row per seed (the BENCHMARKS.md hold
# figures): RMS and max hold error, estimate drift, crashed, recovery after the push.
#   bash scripts/holds.sh FIRST_SEED LAST_SEED [extra `plumbline sim` arguments...]
set -euo pipefail
cd "$(dirname "$0")/.."
first=${1:?first seed}
last=${2:?last seed}
shift 2
cargo build --release -q -p plumbline
bin=target/release/plumbline
printf 'seed\trms_hold_error_m\tmax_hold_error_m\testimate_drift_m\tcrashed\trecovery_s\n'
for seed in $(seq "$first" "$last"); do
  "$bin" sim --world room --scenario hold --lidar xv11 --controller pid --duration 60 \
    --seed "$seed" --json "$@" | tail -1 | python3 -c "
import json, sys
o = json.load(sys.stdin)
print('\t'.join(str(v) for v in ($seed, o['rms_hold_error_m'], o['max_hold_error_m'],
      o['estimate_drift_m'], o['crashed'], o['recovery_s'])))"
done

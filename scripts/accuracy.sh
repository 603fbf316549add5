#!/usr/bin/env bash
# Relations-metric accuracy of every matcher on the benchmark logs in ../shared/data, lidar-only
# and with the log's odometry as prior. Prints one TSV row per run (the BENCHMARKS.md table).
#   bash scripts/accuracy.sh [matchers...]
set -euo pipefail
cd "$(dirname "$0")/.."
data=../shared/data
[ -d "$data" ] || { echo "skipped: $data does not exist" >&2; exit 0; }
cargo build --release -q -p plumbline
bin=target/release/plumbline
out=$(mktemp -d)
matchers=${*:-icl plicp icp icl-paper}
printf 'log\tmatcher\tprior\ttrans_mean_m\tnear_m\tfar_m\trot_mean_deg\tmatched\tfailed\tmedian_us\n'
for set in "intel-lab/intel-first5505.derived.clf intel-lab/intel.relations intel" \
           "mit-csail/mit-csail.clf mit-csail/mit-csail.relations mit"; do
  read -r log rel name <<<"$set"
  for m in $matchers; do
    for prior in "" "--odom-prior"; do
      o=$($bin odometry "$data/$log" --matcher "$m" $prior --out "$out/t.txt" --json 2>/dev/null | tail -1)
      e=$($bin eval "$out/t.txt" "$data/$rel" --json 2>/dev/null | tail -1)
      python3 - "$name" "$m" "${prior:-none}" "$o" "$e" <<'PY'
import json, sys
name, m, prior, o, e = sys.argv[1:6]
o, e = json.loads(o), json.loads(e)
print("\t".join([name, m, "odometry" if prior != "none" else "lidar-only",
                 f"{e['trans_mean_m']:.3f}", f"{e['near_trans_mean_m']:.3f}", f"{e['far_trans_mean_m']:.3f}",
                 f"{e['rot_mean_deg']:.2f}", f"{e['matched']}/{e['relations']}", str(o['failed_matches']),
                 f"{o['median_match_us']:.0f}"]))
PY
    done
  done
done

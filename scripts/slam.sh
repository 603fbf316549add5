#!/usr/bin/env bash
# SLAM figures for BENCHMARKS.md: the benchmark logs at full rate and thinned to every 4th and
# 8th scan (lidar-only), scored by the relations metric, with odometry in the same run; then
# simulated surveys (de-skewed for their lidar) scored against their truth and walls. One TSV
# row per run.
#   bash scripts/slam.sh
set -euo pipefail
cd "$(dirname "$0")/.."
data=../shared/data
[ -d "$data" ] || { echo "skipped: $data does not exist" >&2; exit 0; }
cargo build --release -q -p plumbline
bin=$PWD/target/release/plumbline
out=$(mktemp -d)
row() { # name command-summary eval-summary
  python3 - "$@" <<'PY'
import json, sys
name, s, e = sys.argv[1], json.loads(sys.argv[2]), json.loads(sys.argv[3]) if sys.argv[3] else {}
keys = ["trans_mean_m", "near_trans_mean_m", "far_trans_mean_m", "rot_mean_deg", "matched"]
skeys = ["loop_closures_accepted", "loop_closures_downweighted", "wall_s", "realtime_factor",
         "median_scan_us", "p99_scan_us", "median_match_us", "p99_match_us", "peak_rss_mb",
         "map_error_m", "map_error_far_fraction"]
f = lambda v: f"{v:.4f}" if isinstance(v, float) else str(v)
print("\t".join([name] + [f"{k}={f(e[k])}" for k in keys if k in e] + [f"{k}={f(s[k])}" for k in skeys if s.get(k) is not None]))
PY
}
for every in 1 4 8; do
  for set in "intel-lab/intel-first5505.derived.clf intel-lab/intel.relations intel" \
             "mit-csail/mit-csail.clf mit-csail/mit-csail.relations mit"; do
    read -r log rel name <<<"$set"
    awk -v k=$every '/^FLASER/{n++; if ((n-1)%k==0) print; next} {print}' "$data/$log" > "$out/log.clf"
    for cmd in slam odometry; do
      s=$("$bin" $cmd "$out/log.clf" --out "$out/t.txt" --json 2>/dev/null | tail -1)
      e=$("$bin" eval "$out/t.txt" "$data/$rel" --json 2>/dev/null | tail -1 || true)
      row "$name/every$every/$cmd" "$s" "$e"
    done
  done
done
for world in office building; do
  for lidar in xv11 urg04lx utm30lx; do
    d="$out/$world-$lidar"
    "$bin" sim --world $world --scenario survey --lidar $lidar --seed 7 --out "$d" --json >/dev/null
    s=$("$bin" slam "$d/scans.clf" --lidar $lidar --out "$d/t.txt" --world $world --truth "$d/truth.txt" \
      --json | tail -1)
    e=$("$bin" eval "$d/t.txt" "$d/truth.relations" --json | tail -1)
    row "sim/$world/$lidar/slam" "$s" "$e"
  done
done
rm -rf "$out"

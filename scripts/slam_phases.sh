#!/usr/bin/env bash
# SLAM on the benchmark logs thinned to every 4th and 8th scan from EVERY starting scan (phase p
# keeps scan n when (n - 1) % k == p; scripts/slam.sh measures phase 0 only). Lidar-only.
# One TSV row per log, k and phase: the relations error and how many relations it rests on (a
# relation survives thinning only if both its scans do, about 1 in k², so MIT every 8th keeps
# 1-5), the position error against the full-rate SLAM trajectory at the same stamps after the
# best rigid fit (RMS and largest, m: this one sees a divergence whatever relations survive),
# the steps between kept scans that differ from the full-rate path's (where it went wrong
# first, and how: a heading off, or a step cut short along a corridor), and what the run
# reported about being lost (and the wide searches the local map contradicted).
#   bash scripts/slam_phases.sh            (BIN=path/to/plumbline to measure another binary)
#   JOBS=2 runs two phases at a time.
set -euo pipefail
cd "$(dirname "$0")/.."
data=../shared/data
[ -d "$data" ] || { echo "skipped: $data does not exist" >&2; exit 0; }
if [ -z "${BIN:-}" ]; then
  cargo build --release -q -p plumbline
  BIN=$PWD/target/release/plumbline
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
export BIN data out
logs="intel-lab/intel-first5505.derived.clf:intel-lab/intel.relations:intel mit-csail/mit-csail.clf:mit-csail/mit-csail.relations:mit"
for set in $logs; do
  IFS=: read -r log _ name <<<"$set"
  "$BIN" slam "$data/$log" --out "$out/$name-full.txt" >/dev/null
done
one() { # k phase log relations name
  local k=$1 ph=$2 log=$3 rel=$4 name=$5
  local f=$out/$name-$k-$ph
  awk -v k="$k" -v p="$ph" '/^FLASER/{n++; if ((n-1)%k==p) print; next} {print}' "$data/$log" > "$f.clf"
  local s e
  s=$("$BIN" slam "$f.clf" --out "$f.txt" --json 2>/dev/null | tail -1)
  e=$("$BIN" eval "$f.txt" "$data/$rel" --json 2>/dev/null | tail -1 || true)
  python3 - "$name/every$k/phase$ph" "$s" "$e" "$out/$name-full.txt" "$f.txt" > "$f.row" <<'PY'
import json, math, sys
name, s = sys.argv[1], json.loads(sys.argv[2])
e = json.loads(sys.argv[3]) if sys.argv[3] else {}
def load(path):
    return {round(float(l.split()[0]), 4): tuple(map(float, l.split()[1:4]))
            for l in open(path) if l.strip() and not l.startswith("#")}
full, thin = load(sys.argv[4]), load(sys.argv[5])
stamps = sorted(t for t in thin if t in full)
a = [full[t][:2] for t in stamps]; b = [thin[t][:2] for t in stamps]
def between(p, q):  # q in p's frame
    c, s = math.cos(p[2]), math.sin(p[2])
    dx, dy = q[0] - p[0], q[1] - p[1]
    return c*dx + s*dy, -s*dx + c*dy, math.remainder(q[2] - p[2], math.tau)
# Each step between kept scans against the full-rate path's: wrong when off by more than
# 0.3 m or 0.1 rad; "turned" when the heading is off, "short" when only the length falls short
# (a slide back along a corridor), and when the first wrong step came (s from the start).
wrong, turned, short, first = 0, 0, 0, "-"
for p, q in zip(stamps, stamps[1:]):
    f, h = between(full[p], full[q]), between(thin[p], thin[q])
    off_m, off_rad = math.hypot(f[0]-h[0], f[1]-h[1]), abs(math.remainder(f[2]-h[2], math.tau))
    if off_m > 0.3 or off_rad > 0.1:
        wrong += 1
        turned += off_rad > 0.1
        short += off_rad <= 0.1 and math.hypot(h[0], h[1]) < math.hypot(f[0], f[1]) - 0.3
        first = first if wrong > 1 else f"{q - stamps[0]:.1f}"
ma = [sum(p[i] for p in a) / len(a) for i in (0, 1)]
mb = [sum(p[i] for p in b) / len(b) for i in (0, 1)]
# The rotation that best lays the thinned path on the full-rate one (2-D Procrustes).
dot = sum((q[0]-mb[0])*(p[0]-ma[0]) + (q[1]-mb[1])*(p[1]-ma[1]) for p, q in zip(a, b))
crs = sum((q[0]-mb[0])*(p[1]-ma[1]) - (q[1]-mb[1])*(p[0]-ma[0]) for p, q in zip(a, b))
c, s_ = math.cos(math.atan2(crs, dot)), math.sin(math.atan2(crs, dot))
err = [math.hypot(c*(q[0]-mb[0]) - s_*(q[1]-mb[1]) + ma[0] - p[0],
                  s_*(q[0]-mb[0]) + c*(q[1]-mb[1]) + ma[1] - p[1]) for p, q in zip(a, b)]
rms = math.sqrt(sum(x*x for x in err) / len(err))
rel = f"{e['trans_mean_m']:.4f}" if e.get("matched") else "-"
print("\t".join([name, f"trans_mean_m={rel}", f"matched={e.get('matched', 0)}",
                 f"rms_vs_full_m={rms:.3f}", f"max_vs_full_m={max(err):.2f}",
                 f"wrong_steps={wrong}/{len(stamps) - 1}", f"turned={turned}", f"short={short}",
                 f"first_wrong_s={first}",
                 f"predicted_scans={s['predicted_scans']}", f"lost_s={s['lost_s']:.1f}",
                 f"relocalizations={s['relocalizations']}",
                 f"relocalizations_unconfirmed={s.get('relocalizations_unconfirmed', '-')}"]))
PY
  rm -f "$f.clf" "$f.txt"
}
export -f one
for k in 4 8; do
  for set in $logs; do
    IFS=: read -r log rel name <<<"$set"
    for ((ph = 0; ph < k; ph++)); do echo "$k $ph $log $rel $name"; done
  done
done | xargs -P "${JOBS:-1}" -L1 bash -c 'one "$@"' _
for k in 4 8; do
  for set in $logs; do
    IFS=: read -r _ _ name <<<"$set"
    for ((ph = 0; ph < k; ph++)); do cat "$out/$name-$k-$ph.row"; done
  done
done

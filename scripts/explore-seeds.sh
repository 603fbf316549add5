#!/usr/bin/env bash
# Exploration over many seeds: one TSV row per flight of `plumbline sim --scenario explore`
# (people walking), and a summary per world and guidance on stderr: flights, collisions (total),
# smallest clearance, mean and smallest explored fraction, flights home and landed.
#   bash scripts/explore-seeds.sh [FIRST_SEED] [SEEDS] [DURATION_S] [WORLDS...]
# Defaults: seeds 1..100, 600 s, office building intel, both guidances, the XV-11.
# LIDAR=urg04lx and GUIDANCE="frontier" narrow a run; JOBS=N flies N at a time; BIN=PATH flies
# a given plumbline binary instead of building this checkout (so a build cannot swap it mid-run).
set -euo pipefail
cd "$(dirname "$0")/.."
first=${1:-1}
seeds=${2:-100}
duration=${3:-600}
shift $(( $# < 3 ? $# : 3 ))
worlds=${*:-office building intel}
lidar=${LIDAR:-xv11}
guidances=${GUIDANCE:-frontier wall-follow}
jobs=${JOBS:-1}
if [[ -z ${BIN:-} ]]; then
  cargo build --release -q -p plumbline
fi
bin=${BIN:-target/release/plumbline}
rows=$(mktemp)
flights=$(mktemp -d)
trap 'rm -rf "$rows" "$flights"' EXIT
# Each flight writes its row to a file of its own, so rows from parallel jobs never interleave;
# they are printed in seed order once a world's flights are done.
fly() {
  local world=$1 guidance=$2 seed=$3
  "$bin" sim --world "$world" --scenario explore --lidar "$lidar" --guidance "$guidance" \
    --seed "$seed" --duration "$duration" --json 2>/dev/null | tail -1 | python3 -c '
import json, sys
s = json.loads(sys.stdin.read())
f = lambda k: "" if s.get(k) is None else (f"{s[k]:.4f}" if isinstance(s[k], float) else str(s[k]))
print("\t".join([s["world"], s["guidance"], str(s["seed"])] + [f(k) for k in (
    "explored_fraction", "time_to_90pct_s", "collisions", "min_clearance_m", "returned_home",
    "home_error_m", "landed", "map_error_m", "distance_flown_m", "energy_wh", "realtime_factor",
    "failsafe", "status")]))' >"$flights/$world.$guidance.$seed"
}
export -f fly
export bin lidar duration flights
printf 'world\tguidance\tseed\texplored\tt90_s\tcollisions\tmin_clearance_m\treturned\thome_error_m\tlanded\tmap_error_m\tdistance_m\tenergy_wh\trealtime\tfailsafe\tstatus\n'
for world in $worlds; do
  for guidance in $guidances; do
    seq "$first" $((first + seeds - 1)) | xargs -P "$jobs" -I{} bash -c "fly $world $guidance {}"
    for seed in $(seq "$first" $((first + seeds - 1))); do
      cat "$flights/$world.$guidance.$seed"
    done
  done
done | tee "$rows"
python3 - "$rows" <<'PY' >&2
import collections, sys
groups = collections.defaultdict(list)
for line in open(sys.argv[1]):
    c = line.rstrip("\n").split("\t")
    groups[(c[0], c[1])].append(c)
for (world, guidance), rows in sorted(groups.items()):
    seen = [float(r[3]) for r in rows]
    clear = [float(r[6]) for r in rows]
    print(f"{world} {guidance}: {len(rows)} flights, collisions {sum(int(r[5]) for r in rows)}, "
          f"min clearance {min(clear):.3f} m, explored mean {sum(seen)/len(seen):.3f} "
          f"min {min(seen):.3f}, home {sum(r[7] == 'True' for r in rows)}, "
          f"landed {sum(r[9] == 'True' for r in rows)}")
PY

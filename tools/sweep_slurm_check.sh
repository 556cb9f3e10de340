#!/usr/bin/env bash
# CI: `mjtether sweep --slurm` on a real single-node Slurm cluster (tools/slurm_local.sh), as
# root. A manifest of 8 rows of the default scene (currents x tether stiffnesses) runs once as
# a local sweep and once as a 4-task job array plus its merge; the logs must be byte-identical
# and summary.csv identical but for the wall_time column. The daemons are always stopped.
#
#   tools/sweep_slurm_check.sh [BUILD_DIR]      # default: build
set -euo pipefail
cd "$(dirname "$0")/.."
mjtether=$(pwd)/${1:-build}/mjtether
work=$(mktemp -d /tmp/mjtether_slurm.XXXXXX)
cluster=$work/cluster
cleanup() { tools/slurm_local.sh stop "$cluster" || true; }
trap cleanup EXIT

# The manifest: model path relative to it, quoted current lists.
mkdir -p "$work/models"
cp models/rov_tether.xml "$work/models/"
{
  echo "id,model,duration,water.current,tether:umbilical.EA,tether:umbilical.EAc"
  for c in 0.1 0.5; do
    for ea in 1e5 2e5 4e5 8e5; do
      echo "c${c}_EA${ea},models/rov_tether.xml,4,\"$c,0,0\",$ea,$ea"
    done
  done
} > "$work/manifest.csv"

"$mjtether" sweep "$work/manifest.csv" --out "$work/local"

tools/slurm_local.sh start "$cluster"
export SLURM_CONF=$cluster/slurm.conf
"$mjtether" sweep "$work/manifest.csv" --out "$work/slurm" --slurm --tasks 4
read -r array merge < <(bash "$work/slurm/submit.sh")
echo "submitted array job $array, merge job $merge"
for _ in $(seq 600); do
  [[ -z $(squeue -h -j "$array,$merge" 2>/dev/null) ]] && break
  sleep 0.5
done
if [[ -n $(squeue -h -j "$array,$merge" 2>/dev/null) ]]; then
  echo "sweep_slurm_check: jobs still queued after 5 min" >&2
  squeue >&2
  exit 1
fi
tasks=$(ls "$work/slurm"/slurm-"${array}"_*.out | wc -l)
[[ $tasks == 4 ]] || { echo "sweep_slurm_check: $tasks array task outputs, expected 4" >&2; exit 1; }

# Identical logs; identical summaries without wall_time.
status=0
for f in "$work/local"/*.log.csv; do
  cmp "$f" "$work/slurm/$(basename "$f")" || status=1
done
strip() {
  python3 -c '
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
i = rows[0].index("wall_time")
for r in rows: print(r[:i] + r[i+1:])' "$1"
}
diff <(strip "$work/local/summary.csv") <(strip "$work/slurm/summary.csv") || status=1
ok=$(grep -c ',ok,' "$work/slurm/summary.csv" || true)
[[ $ok == 8 ]] || { echo "sweep_slurm_check: $ok rows ok, expected 8" >&2; status=1; }
cleanup
if [[ $status == 0 ]]; then
  echo "sweep_slurm_check: 8 rows, 4 array tasks on Slurm: logs and summary identical to the local sweep"
  rm -rf "$work"
else
  echo "sweep_slurm_check: FAILED; files in $work" >&2
fi
exit $status

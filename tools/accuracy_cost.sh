#!/usr/bin/env bash
# What accuracy costs in time: runs the sweep (tests/bench/accuracy_cost.cc) and draws the
# charts (tools/accuracy_cost.gp) into docs/accuracy_cost/:
#   accuracy_cost.csv   every run: scene, path (engine alone, through MuJoCo, composite rope),
#                       integrator, segments, step, CPU and wall ms per simulated second, errors,
#                       Pareto flags (overall, and within its own path and integrator)
#   accuracy_cost.md    the same as markdown tables, one per scene
#   accuracy_cost_line.png, accuracy_cost_scenes.png   the charts shown in docs/accuracy_cost.md
#   machine.txt         where and when it was measured
# Series: explicit, implicit, implicit2, rk4, bdf2 (engine alone and through MuJoCo), rope.
# About 11 minutes on the 2-core machine (5 of them the 640-segment reference of the line). Usage:
#   tools/accuracy_cost.sh [BUILD_DIR] [driver options, e.g. --scenes line]
#   tools/accuracy_cost.sh --plot-only      (charts again from the committed CSV)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=$root/docs/accuracy_cost
data=$(mktemp -d)
trap 'rm -rf "$data"' EXIT
if [[ "${1:-}" != "--plot-only" ]]; then
  build=${1:-$root/build}
  shift || true
  cmake --build "$build" -j2 --target accuracy_cost
  mkdir -p "$out"
  "$build/tests/bench/accuracy_cost" --out "$data" "$@"
  cp "$data/accuracy_cost.csv" "$data/accuracy_cost.md" "$out/"
  {
    echo "measured: $(date -u '+%Y-%m-%d %H:%M UTC')"
    echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'), $(nproc) cores, $(grep -m1 'cpu MHz' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //') MHz"
    echo "load average at the end: $(cut -d' ' -f1-3 /proc/loadavg)"
    echo "compiler: $(c++ --version | head -1); build: $(grep CMAKE_BUILD_TYPE: "$build/CMakeCache.txt" | cut -d= -f2)"
    echo "MuJoCo: $(dpkg-query -W -f='${Version}' libmujoco-dev 2>/dev/null || echo unknown)"
  } > "$out/machine.txt"
fi
# Plot data, from the CSV: <scene>_<series>.dat (CPU ms/s, err_T, time-only err_T, segments,
# step ms), <scene>_<series>_front.dat, <scene>_front.dat (sorted by cost), <scene>_mean.dat.
awk -F, -v dir="$data" 'NR > 1 {
  series = ($2 == "engine") ? $3 : $2 "_" $3
  print $12 > (dir "/" $1 "_mean.dat")
  if ($13 != 1 || $9 == "nan") next
  line = $7 " " $9 " " $10 " " $4 " " 1000 * $5
  print line > (dir "/" $1 "_" series ".unsorted")
  if ($15 == 1) print line > (dir "/" $1 "_" series "_front.unsorted")
  if ($14 == 1) print line > (dir "/" $1 "_front.unsorted")
}' "$out/accuracy_cost.csv"
for f in "$data"/*.unsorted; do sort -g "$f" > "${f%.unsorted}.dat"; done
gnuplot -e "dir='$data'; out='$out'" "$root/tools/accuracy_cost.gp"
echo "wrote $out"

#!/usr/bin/env bash
# The worked example of docs/sweeps.md: 50 currents x 4 tether stiffnesses on the default
# scene (200 rows of 20 s), swept on every local core, then the summary plotted.
#
#   tools/sweep_example.sh [BUILD_DIR] [OUT_DIR]      # defaults: build, /tmp/mjtether_sweep
#
# Writes docs/sweeps/manifest.csv, runs it into OUT_DIR (resumes if run again), copies the
# summary to docs/sweeps/summary.csv and draws docs/sweeps/peak_tension.png.
set -euo pipefail
cd "$(dirname "$0")/.."
mjtether=$(pwd)/${1:-build}/mjtether
out=${2:-/tmp/mjtether_sweep}
mkdir -p docs/sweeps
# Model paths are relative to the manifest: docs/sweeps/../../models/rov_tether.xml.
{
  echo "id,model,duration,water.current,tether:umbilical.EA,tether:umbilical.EAc"
  for ea in 5e4 1e5 2e5 4e5; do
    for i in $(seq 1 50); do
      c=$(awk -v i="$i" 'BEGIN { printf "%.2f", i * 0.02 }')
      echo "EA${ea}_c${c},../../models/rov_tether.xml,20,\"$c,0,0\",$ea,$ea"
    done
  done
} > docs/sweeps/manifest.csv
"$mjtether" sweep docs/sweeps/manifest.csv --out "$out" || true  # a row may fail: see summary
cp "$out/summary.csv" docs/sweeps/summary.csv
"$mjtether" plot docs/sweeps/summary.csv --x 'water.current[0]' --y peak_tension \
  --by tether:umbilical.EA --out docs/sweeps/peak_tension.png --size 1000x650

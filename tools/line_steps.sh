#!/bin/bash
# Instructions per step (callgrind, deterministic) and interleaved CPU-time medians of the fixed
# line through mj_step, for the libraries of one or two build directories (before/after).
#   tools/line_steps.sh BUILD [BUILD_AFTER] [INTEGRATOR=bdf2] [SEGMENTS=100] [ROUNDS=9]
# A build directory may be a copy of its libmjtether*.so* files (e.g. saved before a change).
# Needs valgrind. The driver is tools/line_steps.cc, compiled against the first directory's
# headers' source tree (this checkout).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
before=$(cd "$1" && pwd)
after=${2:+$(cd "$2" && pwd)}
integ=${3:-bdf2}; seg=${4:-100}; rounds=${5:-9}
bin=$(mktemp -d)/line_steps
trap 'rm -rf "$(dirname "$bin")"' EXIT
c++ -O2 -std=c++17 -I"$here/tests" -I"$here/plugin" -I"$here/src" -isystem /usr/include/eigen3 \
  "$here/tools/line_steps.cc" -o "$bin" -L"$before" -lmjtether -lmjtether_core -lmujoco
per_step() {  # instructions per step: 1000 steps minus none, after a 2000-step warm-up
  local a b
  a=$(LD_LIBRARY_PATH=$1 valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" "$integ" "$seg" 1000 2000 2>&1 | awk '/Collected/{print $4}')
  b=$(LD_LIBRARY_PATH=$1 valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bin" "$integ" "$seg" 0 2000 2>&1 | awk '/Collected/{print $4}')
  echo $(((a - b) / 1000))
}
for lib in "$before" $after; do
  echo "$lib: $(LD_LIBRARY_PATH=$lib "$bin" "$integ" "$seg" 5000 1000 | awk '{print $3, $4}'), $(per_step "$lib") instructions/step"
done
[ -n "$after" ] || exit 0
for r in $(seq "$rounds"); do
  LD_LIBRARY_PATH=$before "$bin" "$integ" "$seg" 5000 1000 | awk '{print "b", $6}'
  LD_LIBRARY_PATH=$after "$bin" "$integ" "$seg" 5000 1000 | awk '{print "a", $6}'
done | python3 -c "
import sys, statistics as st
d = {'b': [], 'a': []}
for l in sys.stdin:
    k, v = l.split(); d[k].append(float(v))
b, a = st.median(d['b']), st.median(d['a'])
print('CPU s per 5000 steps, median of $rounds interleaved: before %.4f, after %.4f, ratio %.3f'
      ' (x real time %.0f -> %.0f)' % (b, a, a / b, 10 / b, 10 / a))"

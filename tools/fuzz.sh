#!/usr/bin/env bash
# Builds the libFuzzer target over the declaration parser with clang-14 (AddressSanitizer,
# LeakSanitizer, UndefinedBehaviorSanitizer) into build-fuzz/ and runs it for SECONDS
# (default 60) from a seed corpus of every declaration in models/ and a few edge cases.
# Exit code 0: no crash, no hang (5 s per input), no leak, no broken range promise.
#   tools/fuzz.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
out=build-fuzz
mkdir -p "$out/corpus" "$out/artifacts"
# The whole core (src/*.cc), not a list: tether.cc calls into the integrators since the static
# start (session 11), and a hand-kept list broke this stage's link in CI.
clang++-14 -std=c++17 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
  -fno-omit-frame-pointer -Isrc -isystem /usr/include/eigen3 \
  src/*.cc tests/fuzz/declaration_fuzz.cc -o "$out/declaration_fuzz"
# Seeds: the data="..." of every <text> in the models, and edge cases.
i=0
for f in models/*.xml; do
  # Lines joined first: most declarations span lines. A model without any (grep finds
  # nothing, exit 1) must not stop the script under pipefail.
  { tr '\n' ' ' < "$f" | grep -o 'data="[^"]*"' || true; } | sed -e 's/^data="//' -e 's/"$//' |
    while IFS= read -r seed; do
    printf '%s' "$seed" > "$out/corpus/model_$(basename "$f" .xml)_$i"; i=$((i + 1))
  done
done
printf '%s' 'ends=a,b length=40 segments=40 diameter=0.02 mass_per_length=0.35 EA=2e5 EAc=2e5 EI=0.5 damping=50 Cdn=1.2 Cdt=0.01 Can=1.0 integrator=explicit clamp=A effects=axial,bending,clamp,drag,compression substeps=3 max_strain=2' > "$out/corpus/tether_full"
printf '%s' 'density=1025 current=0.3,0,0 seabed=-60 seabed_stiffness=1e5 seabed_damping=10 seabed_friction=0.5 seabed_friction_axial=0.2 seabed_friction_speed=0.01' > "$out/corpus/water_full"
printf '%s' 'ends=a,b length=20 segments=20 diameter=0.02 mass_per_length=0.35 EA=2e5 integrator=rk4 max_step=1e-4' > "$out/corpus/tether_rk4"
# Regression: a max_step this small overflowed the step count (found by this fuzzer).
printf '%s' 'ends=a,b length=21 segments=19 diameter=0.02 mass_per_length=0.35 EA=2e5 integrator=rk4 max_step=1e-54' > "$out/corpus/tether_tiny_max_step"
printf '%s' 'ends=a,free length=1e5 segments=1e5 diameter=10 mass_per_length=1e5 EA=1e13 EAc=1e13 EI=1e12 max_step=1' > "$out/corpus/tether_extremes"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  "$out/declaration_fuzz" -max_total_time="$seconds" -timeout=5 -rss_limit_mb=2048 \
  -max_len=4096 -print_final_stats=1 -artifact_prefix="$out/artifacts/" "$out/corpus"

#!/usr/bin/env bash
# ThreadSanitizer over the rollouts and the threads test: the passive callback, the vehicle
# glue and the rollout pool are instrumented (libmujoco is not, so races inside MuJoCo itself
# are out of its sight). Builds only those two tests in build-tsan.
#
#   tools/tsan.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMJTETHER_BENCHMARKS=OFF \
  -DCMAKE_CXX_FLAGS="-fsanitize=thread" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread" >/dev/null
cmake --build build-tsan -j"$(nproc)" --target rollout_test robust_test
export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1"
./build-tsan/tests/rollout_test
./build-tsan/tests/robust_test --gtest_filter='*Thread*'
echo "tsan: no data race reported"

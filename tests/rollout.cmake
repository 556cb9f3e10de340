# Rollouts on a thread pool (plugin/rollout.h). tools/tsan.sh builds the same test under
# ThreadSanitizer; the throughput is measured by tests/bench/bench_rollout.cc.
find_package(Threads REQUIRED)
add_executable(rollout_test rollout_test.cc)
target_link_libraries(rollout_test PRIVATE mjtether_plugin GTest::gtest_main Threads::Threads)
target_compile_definitions(rollout_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
gtest_discover_tests(rollout_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

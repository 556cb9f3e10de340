# Parameter sweeps (docs/sweeps.md): declaration overrides, `mjtether run --set/--summary`,
# `mjtether sweep` (local, resume, failing rows, bad input, the Slurm scripts run by hand) and
# `mjtether plot --x --y`. The real single-node Slurm cluster is in .ci/run
# (tools/sweep_slurm_check.sh), not here: it needs root and daemons.
add_executable(sweep_test sweep_test.cc)
target_link_libraries(sweep_test PRIVATE mjtether_plugin GTest::gtest_main)
target_include_directories(sweep_test PRIVATE ${PROJECT_SOURCE_DIR}/cli)
target_compile_definitions(sweep_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(sweep_test mjtether)
gtest_discover_tests(sweep_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS sweep)

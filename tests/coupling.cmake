# Vehicle-tether coupling and the time-step advisor (issue 11, items 1 and 2; docs/coupling.md).
add_executable(coupling_test coupling_test.cc)
target_link_libraries(coupling_test PRIVATE mjtether_plugin GTest::gtest_main)
target_compile_definitions(coupling_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
  MJTETHER_STEP_CHECK_DIR="${CMAKE_CURRENT_SOURCE_DIR}/step_check"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(coupling_test mjtether)
gtest_discover_tests(coupling_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

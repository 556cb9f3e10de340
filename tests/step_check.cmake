# `mjtether run --check-step`: the run against the same scene at a smaller step, each verdict
# checked against the two runs' own logs (docs/step_check.md).
add_executable(step_check_test step_check_test.cc)
target_link_libraries(step_check_test PRIVATE GTest::gtest_main)
target_include_directories(step_check_test PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
target_compile_definitions(step_check_test PRIVATE
  MJTETHER_CLI="$<TARGET_FILE:mjtether>"
  MJTETHER_STEP_CHECK_DIR="${CMAKE_CURRENT_SOURCE_DIR}/step_check"
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
add_dependencies(step_check_test mjtether)
gtest_discover_tests(step_check_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

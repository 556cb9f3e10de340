# Honest start-up (issue 11, item 3): initial shape on the seabed, load-time refusals with their
# cause (through the CLI: exit code 2), the stretched-start warning, divergence causes.
add_executable(startup_test startup_test.cc)
target_link_libraries(startup_test PRIVATE mjtether_plugin GTest::gtest_main)
target_compile_definitions(startup_test PRIVATE MJTETHER_CLI="$<TARGET_FILE:mjtether>"
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
add_dependencies(startup_test mjtether)
gtest_discover_tests(startup_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

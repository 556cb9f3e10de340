# The warning about implicit steps accepted unconverged (StepStatus::stalled_steps), through
# the CLI's stderr (docs/coupling.md, "Stalled implicit steps").
add_executable(stall_test stall_test.cc)
target_link_libraries(stall_test PRIVATE GTest::gtest_main)
target_compile_definitions(stall_test PRIVATE MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(stall_test mjtether)
gtest_discover_tests(stall_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

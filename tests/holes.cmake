# Tests that close the holes found by the mutation catalogue (tools/mutations.cfg,
# docs/mutation.md): tangential drag, anisotropic seabed friction, the ROV's static pitch,
# the parser's range boundaries and the log's columns, each against an independent reference.
add_executable(holes_test holes_test.cc)
target_link_libraries(holes_test PRIVATE mjtether_plugin GTest::gtest_main)
target_compile_definitions(holes_test PRIVATE MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(holes_test mjtether)
gtest_discover_tests(holes_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

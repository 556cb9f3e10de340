# The implicit step on slack tethers (docs/numerics_slack.md): seabed statics, the step's
# residual, the Newton report. Cost figures: tests/bench/bench_slack (not a timed test).
add_executable(slack_test slack_test.cc)
target_link_libraries(slack_test PRIVATE mjtether_core GTest::gtest_main)
gtest_discover_tests(slack_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

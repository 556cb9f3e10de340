# The implicit step's line search on heavily damped slack tethers (docs/numerics_slack.md,
# "Line search on the incremental potential"). Cost figures: tests/bench/bench_slack.
add_executable(slack_linesearch_test slack_linesearch_test.cc)
target_link_libraries(slack_linesearch_test PRIVATE mjtether_core GTest::gtest_main)
gtest_discover_tests(slack_linesearch_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

# The implicit step's piece test at the kink of the discrete damped law and the first
# iteration's taut set carried into the Newton iterations, on heavily damped slack tethers
# (docs/numerics_slack.md, fourth section). Cost figures: tests/bench/bench_slack.
add_executable(slack_kink_test slack_kink_test.cc)
target_link_libraries(slack_kink_test PRIVATE mjtether_core GTest::gtest_main)
gtest_discover_tests(slack_kink_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

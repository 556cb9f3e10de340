# The implicit step's predicted pieces on heavily damped slack tethers (docs/numerics_slack.md,
# "Predicted pieces in the Newton iteration"). Cost figures: tests/bench/bench_slack.
add_executable(slack_predict_test slack_predict_test.cc)
target_link_libraries(slack_predict_test PRIVATE mjtether_core GTest::gtest_main)
gtest_discover_tests(slack_predict_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

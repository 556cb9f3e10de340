# The winch (issue 13, docs/winch.md): payout and haul-in through MuJoCo against closed forms,
# limits, constant tension, seabed, every integrator, copies and resets, bad declarations.
# Cost per inserted node: tests/bench/bench_winch (not a timed test).
add_executable(winch_test winch_test.cc)
target_link_libraries(winch_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(winch_test DISCOVERY_TIMEOUT 60)

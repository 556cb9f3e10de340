# The winch (issue 13, docs/winch.md): payout and haul-in through MuJoCo against closed forms,
# limits, constant tension, seabed, every integrator, copies and resets, bad declarations.
# Cost per inserted node: tests/bench/bench_winch (not a timed test).
add_executable(winch_test winch_test.cc)
target_link_libraries(winch_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(winch_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)
# Quasi-static payout in a cross current against an independent static-cable (shooting) reference.
add_executable(winch_current_test winch_current_test.cc)
target_link_libraries(winch_current_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(winch_current_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)
# The winch's reaction on a free TMS body (momentum against the reported drum force).
add_executable(winch_body_test winch_body_test.cc)
target_link_libraries(winch_body_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(winch_body_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

# The controller example's winch mode (examples/rov_pid.cc --winch): a PID flies the BlueROV2
# 20 m down-range while the boat's reel holds 10 N; exit status 0 only if the depth stayed within
# 0.05 m after 5 s, the tension at the drum within 10% of 10 N after 20 s and the vehicle ended
# within 0.5 m of its set-point.
add_test(NAME rov_pid_winch_example
  COMMAND rov_pid ${PROJECT_SOURCE_DIR}/models/bluerov2_heavy_winch.xml --winch 10 --goal 20
          --duration 60 --bound 0.05)

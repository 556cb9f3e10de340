# The explicit schemes' computed stability limit against the measured one on the reference
# scenes of the accuracy/cost sweep (engine only, about 10 s).
add_executable(stable_step_test stable_step_test.cc)
target_link_libraries(stable_step_test PRIVATE mjtether_core GTest::gtest_main)
gtest_discover_tests(stable_step_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

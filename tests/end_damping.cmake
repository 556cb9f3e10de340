# The end's damping too stiff for its body's MuJoCo step (docs/scene_fuzzer.md, failure class
# open-thrust-qacc): the run stops with the cause before MuJoCo's bad-QACC reset.
add_executable(end_damping_test end_damping_test.cc)
target_link_libraries(end_damping_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(end_damping_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

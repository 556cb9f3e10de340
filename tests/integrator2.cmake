# The default integrator bdf2 (issue 17 item 1, docs/numerics.md): observed order 2, the 5 Hz
# wave kept, copies and resets bit-identical with its history, a winch payout (about 10 s).
add_executable(integrator2_test integrator2_test.cc)
target_link_libraries(integrator2_test PRIVATE mjtether_plugin GTest::gtest_main)
target_compile_definitions(integrator2_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
gtest_discover_tests(integrator2_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

# The static start (key start=static; docs/static_start.md): Irvine, a converged dynamic
# reference in a current, the non-convergence warning, and no start transient in MuJoCo.
add_executable(static_start_test static_start_test.cc)
target_link_libraries(static_start_test PRIVATE mjtether_plugin GTest::gtest_main)
target_compile_definitions(static_start_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
gtest_discover_tests(static_start_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

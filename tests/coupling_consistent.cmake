# A light vehicle on a stiff tether at the vehicle step (issue 11 item 1;
# docs/coupling.md).
add_executable(coupling_consistent_test coupling_consistent_test.cc)
target_link_libraries(coupling_consistent_test PRIVATE mjtether_plugin GTest::gtest_main)
target_compile_definitions(coupling_consistent_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
gtest_discover_tests(coupling_consistent_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

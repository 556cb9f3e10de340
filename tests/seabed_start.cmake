# The seabed start shape with EAc: chords of exactly L0 at the path's corners, no force spike
# at the first step (issue 11, item 3).
add_executable(seabed_start_test seabed_start_test.cc)
target_link_libraries(seabed_start_test PRIVATE mjtether_plugin GTest::gtest_main)
target_compile_definitions(seabed_start_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
gtest_discover_tests(seabed_start_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

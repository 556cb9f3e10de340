# The render pipeline (issue 16, item 5): parallel frames byte for byte the serial ones, in
# order, a failing sink stops it; the CLI's stills with 1 and 3 render threads are equal files.
add_executable(pipeline_test pipeline_test.cc)
target_link_libraries(pipeline_test PRIVATE mjtether_render GTest::gtest_main)
target_compile_definitions(pipeline_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(pipeline_test mjtether)
gtest_discover_tests(pipeline_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

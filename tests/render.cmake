# Off-screen rendering (issue 5): pixels where the tether projects, tension colours, and the
# `mjtether render` video checked with ffprobe. Software rendering: the frames are small.
add_executable(render_test render_test.cc)
target_link_libraries(render_test PRIVATE mjtether_render GTest::gtest_main)
target_compile_definitions(render_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(render_test mjtether)
gtest_discover_tests(render_test DISCOVERY_TIMEOUT 60)

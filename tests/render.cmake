# Off-screen rendering (issue 5): pixels where the tether projects, tension colours, and the
# `mjtether render` video checked with ffprobe. Software rendering: the frames are small.
add_executable(render_test render_test.cc)
target_link_libraries(render_test PRIVATE mjtether_render GTest::gtest_main)
target_compile_definitions(render_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(render_test mjtether)
gtest_discover_tests(render_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

# Framing and layout (issue 16): the vehicle seen in the shipped scenes, overlays off the tether,
# smooth camera, overlays that fit at 320x240 and 1920x1080; the CLI's last instant, auto, plot.
add_executable(render_framing_test render_framing_test.cc)
target_link_libraries(render_framing_test PRIVATE mjtether_render GTest::gtest_main)
target_compile_definitions(render_framing_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(render_framing_test mjtether)
gtest_discover_tests(render_framing_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

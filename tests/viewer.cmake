# `mjtether view` under Xvfb (issue 16, item 7): screenshot with tension colours at the
# projected nodes, HUD and overlay; pause/step/reset/speed keys. Only when the viewer is built
# (GLFW found); the test skips itself without xvfb-run.
if(glfw3_FOUND)
  find_package(PNG REQUIRED)
  add_executable(viewer_test viewer_test.cc)
  target_link_libraries(viewer_test PRIVATE mjtether_render PNG::PNG GTest::gtest_main)
  target_compile_definitions(viewer_test PRIVATE MJTETHER_CLI="$<TARGET_FILE:mjtether>")
  add_dependencies(viewer_test mjtether)
  gtest_discover_tests(viewer_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)
endif()

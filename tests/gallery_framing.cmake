# The gallery's framing in every frame (issue 16): for each `render` command of
# renders/make_gallery.sh, every frame it renders is posed as `mjtether render` poses it; the
# vehicle is in the frame and >= 40 px (or in the close-up), the tether off the HUD and scale.
add_executable(gallery_framing_test gallery_framing_test.cc)
target_link_libraries(gallery_framing_test PRIVATE mjtether_render GTest::gtest_main)
target_compile_definitions(gallery_framing_test PRIVATE
  MJTETHER_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
# Label "gallery": minutes of simulation (the workclass run is 300 s simulated, twice); the
# sanitizer run of .ci/run leaves it out (the pose code is under ASan in render_framing_test).
gtest_discover_tests(gallery_framing_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS gallery)

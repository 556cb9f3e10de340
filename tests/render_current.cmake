# The current arrow with a current profile (issue 16, item 6): the arrow shows the current at
# the depth of the view's centre.
add_executable(render_current_test render_current_test.cc)
target_link_libraries(render_current_test PRIVATE mjtether_render GTest::gtest_main)
gtest_discover_tests(render_current_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

# Validation against closed forms and published references (docs/validation.md). The table
# there is generated from this program's output by tools/validation_table.py.
add_executable(validation_test validation_test.cc validation_mujoco_test.cc)
target_link_libraries(validation_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(validation_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS validation)

# The shipped height-field scene models/hfield_rock.xml (issue 12; docs/contact.md, "Height
# fields"): it loads, and the tether dragged over the rock stays on its surface.
add_executable(hfield_rock_test hfield_rock_test.cc)
target_link_libraries(hfield_rock_test PRIVATE mjtether_plugin GTest::gtest_main)
target_compile_definitions(hfield_rock_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
gtest_discover_tests(hfield_rock_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS contact)

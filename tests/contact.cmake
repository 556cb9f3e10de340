# Tether-geom contact (docs/contact.md): capstan, two-way momentum, no tunnelling, resting on
# a slope, declaration errors.
add_executable(contact_test contact_test.cc)
target_link_libraries(contact_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(contact_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS contact)

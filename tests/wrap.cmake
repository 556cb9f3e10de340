# Tether-geom contact beyond contact_test: a drape over a frictionless cylinder and a tether
# wrapped twice round a pile by an orbiting end (docs/contact.md).
add_executable(wrap_test wrap_test.cc)
target_link_libraries(wrap_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(wrap_test DISCOVERY_TIMEOUT 60 PROPERTIES LABELS contact)

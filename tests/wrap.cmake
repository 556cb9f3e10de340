# Tether-geom contact: a vehicle orbiting a vertical pile twice winds the tether round it twice,
# and the tension rises along the sliding wrap as the capstan law says (docs/contact.md).
add_executable(wrap_test wrap_test.cc)
target_link_libraries(wrap_test PRIVATE mjtether_plugin GTest::gtest_main)
# Left out of the ASan run by name: see drape.cmake.
gtest_discover_tests(wrap_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS contact)
# Contact geometry beyond contact_test: mesh geoms (convex hull) against exact distances, and
# which geoms count as an end's own (skipped near that end only).
add_executable(contact_geoms_test contact_geoms_test.cc)
target_link_libraries(contact_geoms_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(contact_geoms_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS contact)

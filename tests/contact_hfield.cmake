# Tether contact with height-field geoms (docs/contact.md, "Height fields"): a ramp against a
# tilted plane, Coulomb on a ramp, statics on a Gaussian ridge, every integrator.
add_executable(contact_hfield_test contact_hfield_test.cc)
target_link_libraries(contact_hfield_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(contact_hfield_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS contact)

# Tether-geom contact beyond contact_test: a drape over a frictionless cylinder with a mass on
# one end, against statics (docs/environment.md).
add_executable(drape_test drape_test.cc)
target_link_libraries(drape_test PRIVATE mjtether_plugin GTest::gtest_main)
# Tens of seconds each in Release (explicit at a small step), minutes under the sanitizers:
# .ci/run leaves them out of its ASan run by name (contact_test covers the same code there).
gtest_discover_tests(drape_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS contact)

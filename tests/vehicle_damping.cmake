# The vehicle's own damping too stiff for MuJoCo's explicit step (VehicleStopped,
# plugin/vehicles.cc): the run stops with the cause before MuJoCo's bad-QACC reset.
add_executable(vehicle_damping_test vehicle_damping_test.cc)
target_link_libraries(vehicle_damping_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(vehicle_damping_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

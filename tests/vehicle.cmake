# Vehicles, thrusters, prescribed motion and the controller example (issue 4).
add_executable(vehicle_test vehicle_test.cc)
target_link_libraries(vehicle_test PRIVATE mjtether_plugin GTest::gtest_main)
target_compile_definitions(vehicle_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
gtest_discover_tests(vehicle_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)
target_include_directories(vehicle_test PRIVATE ${PROJECT_SOURCE_DIR}/examples)

# The controller example as a program: exit status 0 when the depth stayed within the bound.
add_test(NAME rov_pid_example COMMAND rov_pid --surge 20 --duration 60 --bound 0.05)

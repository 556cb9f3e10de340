# Vehicles, thrusters, prescribed motion and the controller example (issue 4).
add_executable(vehicle_test vehicle_test.cc)
target_link_libraries(vehicle_test PRIVATE mjtether_plugin GTest::gtest_main)
target_compile_definitions(vehicle_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
gtest_discover_tests(vehicle_test DISCOVERY_TIMEOUT 60)

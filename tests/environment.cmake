# The water's depth profile of the current and the bathymetry (docs/environment.md): static
# shape in a sheared current against an integrated equilibrium, uniform profile = current.
add_executable(environment_test environment_test.cc)
target_link_libraries(environment_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(environment_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS environment)
target_compile_definitions(environment_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")

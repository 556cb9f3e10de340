# Hard cases, robustness (time-step advisor, divergence, bad input, threads) and the long run
# of the default scene. Tests labelled "long" run the full length on request:
#   ctest --test-dir build -L long        (MJTETHER_LONG=1: one simulated hour, ...)
# and CI runs the rest with -LE long; their shortened versions are part of the normal suite.
find_package(Threads REQUIRED)

add_executable(robust_test robust_test.cc)
target_link_libraries(robust_test PRIVATE mjtether_plugin GTest::gtest_main Threads::Threads)
target_compile_definitions(robust_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(robust_test mjtether)
gtest_discover_tests(robust_test DISCOVERY_TIMEOUT 60)

add_test(NAME long.DefaultSceneOneHour
         COMMAND robust_test --gtest_filter=Scene.DefaultSceneLongRunIsBoundedWithFlatMemory)
set_tests_properties(long.DefaultSceneOneHour PROPERTIES
  LABELS long ENVIRONMENT MJTETHER_LONG=1 TIMEOUT 1800)

add_executable(stress_test stress_test.cc)
target_link_libraries(stress_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(stress_test DISCOVERY_TIMEOUT 60)

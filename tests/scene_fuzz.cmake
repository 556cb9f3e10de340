# The scene fuzzer (docs/scene_fuzzer.md): a fixed seed set of random ROV scenes, each refused
# at load with a checked cause, run to the end in agreement with a 10x smaller step, or stopped
# with a checked cause. Label scene_fuzz. The long run (10,000 scenes) on request:
#   MJTETHER_SCENE_FUZZ_COUNT=10000 build/tests/scene_fuzz_test
find_package(Threads REQUIRED)
add_executable(scene_fuzz_test scene_fuzz_test.cc)
target_link_libraries(scene_fuzz_test PRIVATE mjtether_plugin GTest::gtest_main Threads::Threads)
target_compile_definitions(scene_fuzz_test PRIVATE
  MJTETHER_SCENE_FUZZ_KNOWN="${CMAKE_CURRENT_SOURCE_DIR}/scene_fuzz_known.txt"
  MJTETHER_SCENE_FUZZ_WORLD_KNOWN="${CMAKE_CURRENT_SOURCE_DIR}/scene_fuzz_world_known.txt"
  MJTETHER_SCENE_FUZZ_WORLD_REGRESSIONS="${CMAKE_CURRENT_SOURCE_DIR}/scene_fuzz_world_regressions.txt"
  MJTETHER_SCENE_FUZZ_REGRESSIONS="${CMAKE_CURRENT_SOURCE_DIR}/scene_fuzz_regressions.txt")
gtest_discover_tests(scene_fuzz_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60
                     PROPERTIES LABELS scene_fuzz TIMEOUT 1500)

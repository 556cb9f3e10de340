# Issue 14: the hostile-input suite (tests/hostile/cases.txt through the real binary), and
# observation without side effects plus the mocap-subtree rule (tests/observe_test.cc).
add_executable(hostile_test hostile_test.cc)
target_link_libraries(hostile_test PRIVATE mjtether_core GTest::gtest_main)
target_compile_definitions(hostile_test PRIVATE
  MJTETHER_HOSTILE_DIR="${CMAKE_CURRENT_SOURCE_DIR}/hostile"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(hostile_test mjtether)
# The cases are listed when the binary is linked (gtest_discover_tests runs it after the
# build): a line added to cases.txt must rebuild it, or CTest never runs the new case.
set_source_files_properties(hostile_test.cc PROPERTIES OBJECT_DEPENDS
  "${CMAKE_CURRENT_SOURCE_DIR}/hostile/cases.txt")
gtest_discover_tests(hostile_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS hostile)

add_executable(observe_test observe_test.cc)
target_link_libraries(observe_test PRIVATE mjtether_plugin GTest::gtest_main)
target_include_directories(observe_test PRIVATE ${PROJECT_SOURCE_DIR}/cli ${CLI11_INCLUDE_DIR})
target_compile_definitions(observe_test PRIVATE
  MJTETHER_HOSTILE_DIR="${CMAKE_CURRENT_SOURCE_DIR}/hostile"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(observe_test mjtether)
gtest_discover_tests(observe_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

# The hostile-input generator (tests/hostile_gen_test.cc): the shipped models with random
# user mistakes, through the real binary; 300 scenes in CI, more on request.
add_executable(hostile_gen_test hostile_gen_test.cc)
target_link_libraries(hostile_gen_test PRIVATE mjtether_core GTest::gtest_main Threads::Threads)
target_compile_definitions(hostile_gen_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(hostile_gen_test mjtether)
gtest_discover_tests(hostile_gen_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60
  PROPERTIES LABELS hostile TIMEOUT 1200)

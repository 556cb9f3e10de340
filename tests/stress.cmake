# Hard cases, robustness (time-step advisor, divergence, bad input, threads) and the long run
# of the default scene. The long tests run shortened in the normal suite (2 simulated minutes);
# the full length (one simulated hour, MJTETHER_LONG=1) is registered with the label "long"
# when configured with -DMJTETHER_LONG_TESTS=ON:  ctest --test-dir build -L long
find_package(Threads REQUIRED)

add_executable(robust_test robust_test.cc)
target_link_libraries(robust_test PRIVATE mjtether_plugin GTest::gtest_main Threads::Threads)
target_compile_definitions(robust_test PRIVATE
  MJTETHER_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
  MJTETHER_CLI="$<TARGET_FILE:mjtether>")
add_dependencies(robust_test mjtether)
gtest_discover_tests(robust_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

# The full-length versions, on request: cmake -DMJTETHER_LONG_TESTS=ON, then ctest -L long.
option(MJTETHER_LONG_TESTS "Register the full-length (label long) tests" OFF)
if(MJTETHER_LONG_TESTS)
  add_test(NAME long.DefaultSceneOneHour
           COMMAND robust_test --gtest_filter=Scene.DefaultSceneLongRunIsBoundedWithFlatMemory)
  set_tests_properties(long.DefaultSceneOneHour PROPERTIES
    LABELS long ENVIRONMENT MJTETHER_LONG=1 TIMEOUT 3600)
endif()

add_executable(stress_test stress_test.cc)
target_link_libraries(stress_test PRIVATE mjtether_plugin GTest::gtest_main)
gtest_discover_tests(stress_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60)

# valgrind on the command line: a short run of the default scene and a bad declaration, no
# memory error and no definite or indirect leak (valgrind exits 9 then). Skipped in the
# sanitizer build (the two do not mix).
find_program(VALGRIND_EXECUTABLE valgrind)
if(VALGRIND_EXECUTABLE AND NOT MJTETHER_SANITIZE)
  set(_vg ${VALGRIND_EXECUTABLE} -q --leak-check=full --errors-for-leak-kinds=definite,indirect
          --error-exitcode=9)
  add_test(NAME valgrind.CliRunHasNoLeaks
           COMMAND ${_vg} $<TARGET_FILE:mjtether> run ${PROJECT_SOURCE_DIR}/models/rov_tether.xml
                   --duration 0.2 --log ${CMAKE_CURRENT_BINARY_DIR}/valgrind_log.csv)
  file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/valgrind_bad.xml
       "<mujoco><custom><text name=\"tether:u\" data=\"ends=a,b length=1 segments=0 "
       "diameter=0.01 mass_per_length=0.1 EA=1e3\"/></custom><worldbody><site name=\"a\"/>"
       "<site name=\"b\" pos=\"1 0 0\"/></worldbody></mujoco>")
  add_test(NAME valgrind.CliBadInputHasNoLeaks
           COMMAND sh -c "$0 \"$@\"; test $? -eq 2" ${_vg} $<TARGET_FILE:mjtether> run
                   ${CMAKE_CURRENT_BINARY_DIR}/valgrind_bad.xml --duration 1)
  set_tests_properties(valgrind.CliRunHasNoLeaks valgrind.CliBadInputHasNoLeaks PROPERTIES
                       LABELS valgrind TIMEOUT 600)
endif()

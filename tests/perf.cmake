# Accuracy/cost work (docs/accuracy_cost.md): block-band solver, end reactions from
# windows, order of convergence of the implicit schemes. The sweep itself is
# tools/accuracy_cost.sh (tests/bench/accuracy_cost.cc), not part of CTest.
add_executable(perf_test perf_test.cc)
target_link_libraries(perf_test PRIVATE mjtether_core GTest::gtest_main)
gtest_discover_tests(perf_test NO_PRETTY_VALUES DISCOVERY_TIMEOUT 60 PROPERTIES LABELS perf)

# The Python module (python/): pytest under CTest, the C++ reference run it must reproduce bit
# for bit, and the depth-hold example (examples/depth_hold.py).
if(MJTETHER_PYTHON)
  add_executable(python_reference_run python/reference_run.cc)
  target_link_libraries(python_reference_run PRIVATE mjtether_plugin)
  set(_py_env
    "PYTHONPATH=${PROJECT_BINARY_DIR}/python"
    "MJTETHER_CLI=$<TARGET_FILE:mjtether>"
    "MJTETHER_REFERENCE_RUN=$<TARGET_FILE:python_reference_run>"
    "MJTETHER_MODELS_DIR=${PROJECT_SOURCE_DIR}/models")
  add_test(NAME python_pytest
           COMMAND ${MJTETHER_PYTHON_EXECUTABLE} -m pytest -q -p no:cacheprovider
                   ${CMAKE_CURRENT_SOURCE_DIR}/python)
  set_tests_properties(python_pytest PROPERTIES ENVIRONMENT "${_py_env}")
  # The example holds the depth within 5 cm after the first 5 s (exit status 0).
  add_test(NAME python_depth_hold_example
           COMMAND ${MJTETHER_PYTHON_EXECUTABLE} ${PROJECT_SOURCE_DIR}/examples/depth_hold.py
                   --duration 20 --bound 0.05)
  set_tests_properties(python_depth_hold_example PROPERTIES ENVIRONMENT "${_py_env}")
endif()

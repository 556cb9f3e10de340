# The README's minimal model is models/minimal_rov.xml, verbatim.
add_test(NAME readme_minimal_model_is_the_shipped_file
  COMMAND ${CMAKE_COMMAND} -DREADME=${PROJECT_SOURCE_DIR}/README.md
          -DFILE=${PROJECT_SOURCE_DIR}/models/minimal_rov.xml
          -P ${PROJECT_SOURCE_DIR}/tools/readme_block_equals.cmake)

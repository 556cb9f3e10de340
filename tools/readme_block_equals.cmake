# cmake -DREADME=README.md -DFILE=models/minimal_rov.xml -P tools/readme_block_equals.cmake
# Fails unless the README contains FILE's text verbatim (the README's minimal model is the
# shipped file, so what a user copies from the README is what the tests run).
file(READ ${README} readme)
file(READ ${FILE} model)
string(FIND "${readme}" "${model}" at)
if(at EQUAL -1)
  message(FATAL_ERROR "${README} does not contain ${FILE} verbatim: update one from the other")
endif()

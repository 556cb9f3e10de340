# Packaging and command-line conveniences (issue 15): `mjtether --version` names this version
# and the MuJoCo it runs on; rov_pid --help prints its usage (it used to load a file called
# --help), and an unknown option is refused. The install, find_package, .deb and Python-prefix
# checks are tools/consumer_check.sh (CI).
add_test(NAME cli_version COMMAND mjtether --version)
string(REPLACE "." "\\." _version_re "${PROJECT_VERSION}")
set_tests_properties(cli_version PROPERTIES
  PASS_REGULAR_EXPRESSION "^mjtether ${_version_re} \\(MuJoCo [0-9]+\\.[0-9]+\\.[0-9]+\\)\n$")
if(MJTETHER_EXAMPLES)
  add_test(NAME rov_pid_help COMMAND rov_pid --help)
  set_tests_properties(rov_pid_help PROPERTIES PASS_REGULAR_EXPRESSION "^usage: rov_pid ")
  add_test(NAME rov_pid_unknown_option COMMAND rov_pid --no-such-option)
  set_tests_properties(rov_pid_unknown_option PROPERTIES WILL_FAIL TRUE)
endif()

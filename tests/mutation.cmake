# Every entry of the mutation catalogue (tools/mutations.cfg) still finds its text exactly once
# in the code (tools/mutate.py --list: no build). CI runs only the sample of 10, so an entry
# whose pattern a change stopped matching went unnoticed (winch-drum-impedance-bdf2-step,
# session 29 to 30).
find_program(MJTETHER_PYTHON3 python3)
if(MJTETHER_PYTHON3)
  add_test(NAME mutation_catalogue_patterns_match
           COMMAND ${MJTETHER_PYTHON3} ${PROJECT_SOURCE_DIR}/tools/mutate.py --list)
endif()

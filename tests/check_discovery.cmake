# Fails when ctest knows fewer core tests than the executable has: Catch2's
# discovery writes the names into a CMake list, and a name with an unbalanced
# bracket or a semicolon silently merges every later test into one entry that
# matches nothing (a green run with most tests never run).
#   cmake -DEXE=<omis_core_tests> -DDIR=<its build dir> -P check_discovery.cmake
# (Catch2 2.x exits with the number of tests listed, not 0.)
execute_process(COMMAND "${EXE}" --list-test-names-only OUTPUT_VARIABLE names)
if(names STREQUAL "")
    message(FATAL_ERROR "${EXE} --list-test-names-only listed nothing")
endif()
# Counted by markers, not as CMake lists: a ';' in a name would split those.
string(REGEX MATCHALL "\n" newlines "${names}")
list(LENGTH newlines expected)
file(GLOB discovered_files "${DIR}/omis_core_tests_tests-*.cmake")
set(discovered 0)
foreach(f IN LISTS discovered_files)
    file(READ "${f}" text)
    string(REGEX MATCHALL "add_test\\(" calls "${text}")
    list(LENGTH calls n)
    math(EXPR discovered "${discovered} + ${n}")
endforeach()
if(NOT discovered EQUAL expected)
    message(FATAL_ERROR "ctest runs ${discovered} core tests but ${EXE} has ${expected}: "
                        "a TEST_CASE name has an unbalanced '[' or ']' or a ';'")
endif()
message(STATUS "${discovered} core tests discovered, as listed")

# cmake -DCXX=compiler -DSOURCE_DIR=repository -DINCLUDES=dir|dir -P layouts_compile_test.cmake
# The table's indices at compile time: the probe compiles with a known field
# name and fails, at the unknown name, with a misspelt one.
string(REPLACE "|" ";" includes "${INCLUDES}")
set(flags -std=c++17 -fsyntax-only -I${SOURCE_DIR})
foreach(dir ${includes})
  list(APPEND flags -I${dir})
endforeach()
set(probe ${SOURCE_DIR}/tests/bridge/layouts_constexpr_probe.cc)

execute_process(COMMAND ${CXX} ${flags} ${probe} RESULT_VARIABLE known ERROR_VARIABLE known_errors)
if(NOT known EQUAL 0)
  message(FATAL_ERROR "the probe with a known field does not compile:\n${known_errors}")
endif()

execute_process(COMMAND ${CXX} ${flags} -DVLAB_PROBE_UNKNOWN_FIELD ${probe} RESULT_VARIABLE unknown
                ERROR_VARIABLE unknown_errors)
if(unknown EQUAL 0)
  message(FATAL_ERROR "StateIndex(kGripper, \"grasp\") compiled as a constant: a misspelt field must not")
endif()
if(NOT unknown_errors MATCHES "ThrowNoField")
  message(FATAL_ERROR "the probe with a misspelt field failed, but not at the field lookup:\n${unknown_errors}")
endif()
message(STATUS "a known field is a constant; a misspelt one does not compile")

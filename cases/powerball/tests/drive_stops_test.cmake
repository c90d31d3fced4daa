# Run as: cmake -DVLAB=<vlab> -DCASE=<cases/powerball> -DOUT=<folder> -P drive_stops_test.cmake
# Stage 1 with the drive stopped at 20 s (powerball_spin --stop-at 20): the rotor coasts on its
# losses (mjcf/powerball/README.md, "Losses"), so the hold check must fail, and only checks of
# the rotor's speed may: the arm stays inside its limits and the tips still roll.
cmake_policy(SET CMP0057 NEW)  # if(IN_LIST)
file(REMOVE_RECURSE ${OUT})
set(command "[\"{bin}/cases/powerball/powerball_spin\", \"--arm\", \"{pa10}\", \"--jr3\", \"{jr3}\", \"--counter\", \"{pb}\",\
 \"--target-rpm\", \"12000\", \"--stop-at\", \"20\", \"--quiet\"]")
execute_process(COMMAND ${VLAB} run ${CASE}/stage1.yaml --quiet --out ${OUT} --set "controller.command=${command}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out TIMEOUT 200)
if(NOT rc EQUAL 1)
  message(FATAL_ERROR "expected exit 1 (a check failed), got ${rc}:\n${out}")
endif()
file(READ ${OUT}/summary.json summary)
string(JSON n LENGTH "${summary}" checks)
math(EXPR last "${n} - 1")
set(failed "")
foreach(i RANGE ${last})
  string(JSON name GET "${summary}" checks ${i} name)
  string(JSON pass GET "${summary}" checks ${i} pass)
  string(JSON value GET "${summary}" checks ${i} value)
  if(NOT pass)
    list(APPEND failed ${name})
    message(STATUS "failed as it should: ${name} = ${value}")
  endif()
endforeach()
# the hold check fails; any other that fails is one of the rotor's speed (the arm's limits and the
# tips' rolling hold while it coasts)
if(NOT "counter_holds_speed" IN_LIST failed)
  message(FATAL_ERROR "with the drive stopped at 20 s counter_holds_speed passed (failed: '${failed}')")
endif()
foreach(name ${failed})
  if(NOT name MATCHES "^(counter_holds_speed|counter_above_10000_rpm|spin_above_10000_rpm)$")
    message(FATAL_ERROR "with the drive stopped at 20 s a check other than the rotor's speed failed: ${name}")
  endif()
endforeach()

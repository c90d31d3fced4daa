# Run as: cmake -DVLAB=<vlab> -DCASE=<cases/powerball> -DOUT=<folder> -P repeats_test.cmake
# Stage 1 for 5 s, twice; the two runs' log.csv and spin.csv must be equal byte for byte,
# and the rotor must have gained speed (the controller ran: counter above 2,300 rpm at 5 s,
# the rate law gives about 2,900 rpm).
file(REMOVE_RECURSE ${OUT})
foreach(run a b)
  execute_process(COMMAND ${VLAB} run ${CASE}/stage1.yaml --quiet --duration 5 --out ${OUT}/${run}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out TIMEOUT 100)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "run ${run}: vlab run exit ${rc}:\n${out}")
  endif()
endforeach()
foreach(file log.csv spin.csv)
  execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUT}/a/${file} ${OUT}/b/${file} RESULT_VARIABLE differ)
  if(NOT differ EQUAL 0)
    message(FATAL_ERROR "${file} differs between two lockstep runs of the same scenario and seed")
  endif()
endforeach()
file(STRINGS ${OUT}/a/spin.csv rows)
list(GET rows -1 last)
string(REPLACE "," ";" fields "${last}")
list(GET fields 1 rpm)
if(rpm LESS 2300)
  message(FATAL_ERROR "the counter read ${rpm} rpm at 5 s: no spin-up (expected about 2,900)")
endif()
message(STATUS "two lockstep runs of stage 1 (5 s) are byte-identical; counter ${rpm} rpm at 5 s")

# Run as: cmake -DVLAB=<vlab> -DCASE=<cases/cubes> -DOUT=<folder> -P stage1_repeat.cmake
# Stage 1, seed 2 in full and again cut at 30 s (the first look, the first letter picked):
# lockstep with the vision program beside it, the cut run's log.csv must equal the first rows
# of the full run's byte for byte.
file(REMOVE_RECURSE ${OUT})
string(TIMESTAMP start "%s")
execute_process(COMMAND ${VLAB} run ${CASE}/stage1.yaml --seed 2 --quiet --out ${OUT}/seed2
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out TIMEOUT 280)
string(TIMESTAMP end "%s")
math(EXPR wall "${end} - ${start}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "stage 1, seed 2: vlab run exit ${rc}:\n${out}")
endif()
message(STATUS "stage 1, seed 2: pass (${wall} s wall)")
execute_process(COMMAND ${VLAB} run ${CASE}/stage1.yaml --seed 2 --duration 30 --quiet --out ${OUT}/seed2_cut
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out TIMEOUT 120)
# the cut run's checks may fail (the word is not spelled at 30 s); it must have run to its end
if(NOT EXISTS ${OUT}/seed2_cut/log.csv)
  message(FATAL_ERROR "stage 1, seed 2, 30 s: no log.csv (exit ${rc}):\n${out}")
endif()
file(STRINGS ${OUT}/seed2_cut/log.csv cut)
file(STRINGS ${OUT}/seed2/log.csv full)
list(LENGTH cut n)
if(n LESS 2000)
  message(FATAL_ERROR "stage 1, seed 2, 30 s: only ${n} log rows")
endif()
list(SUBLIST full 0 ${n} head)
if(NOT cut STREQUAL head)
  message(FATAL_ERROR "stage 1, seed 2: the 30 s run's log differs from the first ${n} rows of the full run's")
endif()
message(STATUS "stage 1, seed 2: the 30 s run's ${n} log rows equal the full run's byte for byte")

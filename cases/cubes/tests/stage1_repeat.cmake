# Run as: cmake -DVLAB=<vlab> -DCASE=<cases/cubes> -DFULL=<seed 2's full run> -DOUT=<folder> -P stage1_repeat.cmake
# Stage 1, seed 2 cut at 30 s (the first look, the first letter picked): lockstep with the
# vision program beside it, the cut run's log.csv must equal the first rows of FULL/log.csv,
# the full run of seed 2 that cubes_stage1_seeds made (beside seed 1) and passed.
file(REMOVE_RECURSE ${OUT})
if(NOT EXISTS ${FULL}/log.csv)
  message(FATAL_ERROR "stage 1, seed 2: no full run in ${FULL} (cubes_stage1_seeds makes it)")
endif()
execute_process(COMMAND ${VLAB} run ${CASE}/stage1.yaml --seed 2 --duration 30 --quiet --out ${OUT}/seed2_cut
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out TIMEOUT 120)
# the cut run's checks may fail (the word is not spelled at 30 s); it must have run to its end
if(NOT EXISTS ${OUT}/seed2_cut/log.csv)
  message(FATAL_ERROR "stage 1, seed 2, 30 s: no log.csv (exit ${rc}):\n${out}")
endif()
file(STRINGS ${OUT}/seed2_cut/log.csv cut)
file(STRINGS ${FULL}/log.csv full)
list(LENGTH cut n)
if(n LESS 2000)
  message(FATAL_ERROR "stage 1, seed 2, 30 s: only ${n} log rows")
endif()
list(SUBLIST full 0 ${n} head)
if(NOT cut STREQUAL head)
  message(FATAL_ERROR "stage 1, seed 2: the 30 s run's log differs from the first ${n} rows of the full run's")
endif()
message(STATUS "stage 1, seed 2: the 30 s run's ${n} log rows equal the full run's byte for byte")

# The yo-yo stages test (ctest yoyo_stages), run by ctest as
#   cmake -DCASE=<cases/yoyo> -DRUNS=<scenario-out> -P stages_test.cmake
# The three shipped stage scenarios must pass with the SAME yoyo_control binary (its `binary
# PATH fnv1a64 HASH` line in each run's controller.log), each reading the yo-yo from where its
# stage says. Each stage runs once in the suite, as its shipped-scenario test
# (scenario_yoyo_stage1, _stage2, _stage3: this test's fixtures, ctest runs them first and side
# by side); this test reads their runs in RUNS/yoyo_stage1, _stage2, _stage3. Prints each
# stage's amplitude error (max |top - level| / level over the checked swings).
set(hashes "")
set(stages stage1 stage2 stage3)
file(READ ${CASE}/stage3.yaml stage3_text)
string(REGEX MATCH "\nduration: ([0-9]+)" _ "${stage3_text}")  # whole seconds
set(stage3_duration "${CMAKE_MATCH_1}")
foreach(stage ${stages})
  set(run ${RUNS}/yoyo_${stage})
  if(NOT EXISTS ${run}/controller.log)
    message(FATAL_ERROR "${stage}: no run in ${run} (scenario_yoyo_${stage} runs it: ctest runs that test first)")
  endif()
  file(READ ${run}/controller.log log)
  string(REGEX MATCH "fnv1a64 ([0-9a-f]+)" _ "${log}")
  set(hash "${CMAKE_MATCH_1}")
  string(REGEX MATCH "amplitude error ([0-9.]+)" _ "${log}")
  set(error "${CMAKE_MATCH_1}")
  message(STATUS "${stage}: controller fnv1a64 ${hash}, amplitude error ${error}")
  if(error STREQUAL "" OR hash STREQUAL "")
    message(FATAL_ERROR "${stage}: no amplitude error or binary hash in ${run}/controller.log:\n${log}")
  endif()
  # where the yo-yo came from: the lab's model (1), vlab-yoyosim (2), vlab vision's tracker
  # fed by the lab's webcam, every frame seen (3)
  string(REGEX MATCH "yo-yo from '[^']*' \\(([^)]*)\\)" _ "${log}")
  set(source "${CMAKE_MATCH_1}")
  set(expected_source "vlab serve;vlab-yoyosim;vlab vision")
  list(FIND stages ${stage} i)
  list(GET expected_source ${i} expected)
  if(NOT source MATCHES "^${expected}")
    message(FATAL_ERROR "${stage}: the controller read the yo-yo from '${source}', not from ${expected}:\n${log}")
  endif()
  if(stage STREQUAL "stage3")
    string(REGEX MATCH "vlab vision: ([0-9]+) frames[^\n]*yo-yo seen in ([0-9]+)" _ "${log}")
    set(frames "${CMAKE_MATCH_1}")
    set(seen "${CMAKE_MATCH_2}")
    # 25 frames/s over the run, less the start's second
    math(EXPR least "(${stage3_duration} - 1) * 25")
    if(frames STREQUAL "" OR frames LESS least OR NOT seen EQUAL frames)
      message(FATAL_ERROR "${stage}: vlab vision saw the yo-yo in '${seen}' of '${frames}' frames (${least} or more, all seen):\n${log}")
    endif()
    message(STATUS "${stage}: vlab vision saw the yo-yo in ${seen} of ${frames} frames")
  endif()
  list(APPEND hashes ${hash})
endforeach()
list(REMOVE_DUPLICATES hashes)
list(LENGTH hashes n)
if(NOT n EQUAL 1)
  message(FATAL_ERROR "the stages ran different controller binaries: ${hashes}")
endif()
message(STATUS "the three stages passed with the same controller (fnv1a64 ${hashes})")


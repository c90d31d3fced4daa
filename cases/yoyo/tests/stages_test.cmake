# The yo-yo stages test (ctest yoyo_stages), run by ctest as
#   cmake -DVLAB=<vlab> -DCASE=<cases/yoyo> -DRUNS=<scenario-out> -DOUT=<output folder> -P stages_test.cmake
# The three shipped stage scenarios must pass with the SAME yoyo_control binary (its `binary
# PATH fnv1a64 HASH` line in each run's controller.log), each reading the yo-yo from where its
# stage says. Each stage runs once in the suite: stages 1 and 2 are the shipped-scenario tests
# scenario_yoyo_stage1 and _stage2 (this test's fixtures: it reads their runs in
# RUNS/yoyo_stage1, RUNS/yoyo_stage2), stage 3 runs here, whole (tests/scenarios leaves it to
# this test). Prints each stage's amplitude error (max |top - level| / level over the checked swings).
set(hashes "")
set(stages stage1 stage2 stage3)
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${VLAB} run ${CASE}/stage3.yaml --quiet --out ${OUT}/stage3
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out TIMEOUT 150)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "stage3: vlab run exit ${rc}:\n${out}")
endif()
file(READ ${CASE}/stage3.yaml stage3_text)
string(REGEX MATCH "\nduration: ([0-9]+)" _ "${stage3_text}")  # whole seconds
set(stage3_duration "${CMAKE_MATCH_1}")
foreach(stage ${stages})
  if(stage STREQUAL "stage3")
    set(run ${OUT}/stage3)
  else()
    set(run ${RUNS}/yoyo_${stage})
  endif()
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

# A shortened copy of stage 3 for the faults run below: absolute scene and script paths, 25 s,
# the check window [10, 24] s
file(READ ${CASE}/stage3.yaml text)
string(REGEX REPLACE "\nscene: ([^ \n]+)" "\nscene: ${CASE}/\\1" text "${text}")
string(REPLACE "{scenario_dir}" "${CASE}" text "${text}")
string(REPLACE "\"--check-from\", \"15\", \"--check-for\", \"30\"" "\"--check-from\", \"10\", \"--check-for\", \"14\""
       text "${text}")
if(NOT text MATCHES "\"--check-for\", \"14\"")
  message(FATAL_ERROR "stage3: the check window of ${CASE}/stage3.yaml was not found")
endif()
file(WRITE ${OUT}/stage3_short.yaml "${text}")

# Stage 3 again, with a lost and a late frame injected by the webcam (docs/scenarios.md,
# camera `drop_frames`, `late_frames`): frame 375 (t = 15 s) never sent, frame 450 (18 s)
# held 0.12 s (three frames' time, the frames behind it with it), both within the checked
# swings [10, 24] s. The controller and vlab vision must ride through them: the same checks
# and amplitude bound as the plain run.
execute_process(COMMAND ${VLAB} run ${OUT}/stage3_short.yaml --quiet --duration 25 --out ${OUT}/stage3_faults
                        --set "devices.webcam.drop_frames=[375]" --set "devices.webcam.late_frames=[450]"
                        --set "devices.webcam.late_by=0.12"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out TIMEOUT 120)
file(READ ${OUT}/stage3_faults/controller.log log)
string(REGEX MATCH "amplitude error ([0-9.]+)" _ "${log}")
set(error "${CMAKE_MATCH_1}")
if(NOT rc EQUAL 0 OR error STREQUAL "")
  message(FATAL_ERROR "stage3 with a lost and a late frame failed:\n${out}\ncontroller.log:\n${log}")
endif()
# the faults happened: the webcam counted them (at least them: on a loaded machine a worker
# that falls a ring of frames behind drops more, and frames rendered after their due
# period are late too)
file(READ ${OUT}/stage3_faults/summary.json summary)
string(JSON ndev LENGTH "${summary}" bridge devices)
set(dropped "")
math(EXPR last "${ndev} - 1")
foreach(i RANGE ${last})
  string(JSON name GET "${summary}" bridge devices ${i} name)
  if(name STREQUAL "webcam")
    string(JSON dropped GET "${summary}" bridge devices ${i} frames dropped)
    string(JSON late GET "${summary}" bridge devices ${i} frames late)
  endif()
endforeach()
string(REGEX MATCH "vlab vision: ([0-9]+) frames[^\n]*, ([0-9]+) skipped" _ "${log}")
set(skipped "${CMAKE_MATCH_2}")
if(dropped STREQUAL "" OR dropped LESS 1 OR late LESS 3)
  message(FATAL_ERROR "stage3 faults not injected as asked: webcam dropped '${dropped}' (>= 1), late '${late}' "
                      "(>= 3: frame 450 and the two due behind it)\n${log}")
endif()
message(STATUS "stage3 with frame 375 lost and frame 450 0.12 s late: pass, amplitude error ${error}; "
               "webcam dropped ${dropped}, late ${late}; vlab vision skipped ${skipped}")

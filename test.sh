#!/usr/bin/env bash
# vlab test suite: install what is missing, build (warnings are errors: VLAB_WERROR), run
# every test through ctest. With VLAB_SANITIZE=1, also the sanitizer lane (tools/sanitize.sh:
# the unit tests under AddressSanitizer + UndefinedBehaviorSanitizer, in build-asan/): its build
# runs beside the suite in the idle scheduling class (SCHED_IDLE, nice 19), so it takes only the
# CPU time the suite leaves unused (the realtime tests run alone and sleep between periods) and
# yields the moment a test wants a core; its unit tests run after the suite.
#   ./test.sh [ctest options]      e.g. ./test.sh -R physics
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
source tools/setup.sh
vlab_setup --tests
status=0
lane_pid=""
lane_out="build/sanitize-build.out"
if [ "${VLAB_SANITIZE:-0}" = 1 ]; then
  echo "vlab: sanitizer lane: building beside the suite, idle class (log: $lane_out)"
  # in a process group of its own (set -m), so that an interrupted suite stops the whole build
  # with it; in the suite's session all the same: the kernel shares the CPU fairly between
  # sessions (autogroups), and only within one does the idle class yield to the tests
  set -m
  chrt --idle 0 nice -n 19 tools/sanitize.sh --build-only >"$lane_out" 2>&1 &
  lane_pid=$!
  set +m
  trap 'kill -- "-$lane_pid" 2>/dev/null || true' EXIT
fi
(cd build && ctest --output-on-failure -j "$(nproc)" "$@") || status=$?
if [ -n "$lane_pid" ]; then
  lane_status=0
  wait "$lane_pid" || lane_status=$?
  trap - EXIT
  cat "$lane_out"
  if [ "$lane_status" -ne 0 ]; then
    status=$lane_status
  else
    tools/sanitize.sh --test-only || status=$?
  fi
fi
exit $status

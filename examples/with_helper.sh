#!/usr/bin/env bash
# with_helper.sh: runs a helper program in the background and a controller in the
# foreground, for an external controller that needs a second program beside it:
#   with_helper.sh HELPER [ARGS...] -- CONTROLLER [ARGS...]
# The yo-yo stages use it: stage 2 starts vlab-yoyosim beside cases/yoyo/yoyo_control,
# stage 3 starts `vlab vision --yoyo-port` (cases/yoyo/stage2.yaml, stage3.yaml).
# When the controller exits, the helper gets SIGTERM. SIGTERM or SIGINT to this script
# (the end of a `vlab run` signals the whole process group) ends both. The exit status is
# the controller's (a controller the signal ended: this script ends by it too); where the
# controller succeeded and the helper failed on its own (exit 1..125), the helper's.
# Exit 2 on a command line without `--` or without a helper or a controller.
set -u
helper=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do helper+=("$1"); shift; done
if [ $# -eq 0 ] || [ ${#helper[@]} -eq 0 ] || [ $# -eq 1 ]; then
  echo "usage: with_helper.sh HELPER [ARGS...] -- CONTROLLER [ARGS...]" >&2
  exit 2
fi
shift
"${helper[@]}" &
pid=$!
# the controller runs in the foreground, so the trap waits for it to finish (its own check
# on SIGTERM included) and this script gets its exit status as it is (a background `wait`
# interrupted by the trap may report 143 or -1 instead)
signal=
trap 'signal=TERM; kill -TERM $pid 2>/dev/null' TERM
trap 'signal=INT; kill -TERM $pid 2>/dev/null' INT
"$@"
status=$?
kill -TERM $pid 2>/dev/null
wait $pid
helper_status=$?
# the helper's own failures only: 143 is our SIGTERM, and bash may report a child it
# already reaped after the trap as 127 or -1 (255)
if [ $status -eq 0 ] && [ $helper_status -ge 1 ] && [ $helper_status -le 125 ]; then
  echo "with_helper.sh: ${helper[0]} exited with status $helper_status" >&2
  status=$helper_status
fi
# a controller the signal ended (128 + n): end by the same signal, as it did
if [ -n "$signal" ] && [ $status -gt 128 ]; then
  trap - "$signal"
  kill -"$signal" $$
fi
exit $status

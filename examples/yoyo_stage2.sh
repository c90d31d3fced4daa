#!/usr/bin/env bash
# Yo-yo case study, stage 2: the yo-yo in vlab-yoyosim (lockstep, point 50060, yoyo 50061),
# the PA10 in vlab (its hand = the point device HAND), the same examples/yoyo_control binary
# as in stage 1: it commands HAND and mirrors HAND's measured position to the simulator's
# hand (--mirror), reading the yo-yo from the simulator (string force from its yoyo device).
#   yoyo_stage2.sh BIN HAND [yoyo_control options...]   (BIN: the folder holding vlab)
# Used as the external command of scenes/yoyo_stage2.yaml. SIGTERM ends both; the exit
# status is yoyo_control's (1: the amplitude check failed), or the simulator's if that failed.
set -u
bin=$1 hand=$2
shift 2
"$bin/vlab-yoyosim" --clock lockstep --point-port 50060 --yoyo-port 50061 --quiet \
  --scene "$(dirname "$0")/../mjcf/yoyo/yoyo_moving_hand.xml" &
sim=$!
# the end of a run SIGTERMs the whole process group (this script, the simulator and the
# controller); the controller runs in the foreground, so the trap waits for it to finish its
# check and this script has its exit status as it is (a background `wait` interrupted by
# the trap may report 143 or -1 instead)
trap 'kill -TERM $sim 2>/dev/null' TERM INT
"$bin/examples/yoyo_control" --hand "$hand" --mirror 127.0.0.1:50060 --yoyo 127.0.0.1:50061 "$@"
status=$?
kill -TERM $sim 2>/dev/null
wait $sim
sim_status=$?
# the simulator's own failures only (1 diverged, 2 bad input): bash may report a child it
# already reaped after the trap as -1 or 127, and 143 is our SIGTERM
if [ $status -eq 0 ] && { [ $sim_status -eq 1 ] || [ $sim_status -eq 2 ]; }; then status=$sim_status; fi
exit $status

#!/usr/bin/env bash
# The MATLAB/Octave example (examples/matlab) against vlab serve, run by Octave:
# - vlab_arm_hold connects to the PA10 of scenes/pa10_serve (cookie, describe,
#   subscribe), answers each of the 1000 lockstep periods of a 2 s run, renews its
#   subscription on the way and unsubscribes;
# - vlab_simulink_loop runs the Simulink block's code (vlab_simulink_session) the way
#   the model of docs/protocol.md would, for the 100 periods of a 0.2 s run.
# Each run must pass with every command accepted and no lockstep timeout, and the
# script must have answered every seq. Also checks vlab_split_datagrams (what Octave on
# Windows and macOS goes through). Needs octave and its instrument-control package
# (./test.sh installs both); without them the test is skipped (exit 77), reason printed.
# Octave 7 prints "error: ignoring const execution_exception& while preparing to
# exit" at every exit once a package is loaded (Octave bug #62515); it is harmless,
# the exit status is the script's.
#   octave_client_test.sh VLAB OUT_DIR
set -u
vlab="$1"; out="$2"
skip() { echo "SKIPPED: $*"; exit 77; }
octave_eval() { (cd examples/matlab && timeout 30 octave --norc --no-gui --quiet --eval "$1"); }
command -v octave >/dev/null || skip "no octave (./test.sh installs octave and octave-instrument-control)"
octave_eval "pkg('load', 'instrument-control')" >/dev/null 2>&1 ||
  skip "no Octave package instrument-control (Debian: octave-instrument-control)"
rm -rf "$out"; mkdir -p "$out"

# whole datagrams read back to back (a session reply, a 7-joint state) split in two
octave_eval "
  reply = typecast([1447838018 2 1 5 0 0 2 42 1], 'uint8');
  state = typecast([1447838018 2 1 1 7 0.014 22 0 1:21], 'uint8');
  d = vlab_split_datagrams([reply state]);
  assert(numel(d) == 2 && isequal(d{1}, reply) && isequal(d{2}, state));
  d = vlab_split_datagrams(uint8('{\"kind\": \"arm\"}'));
  assert(numel(d) == 1 && d{1}(1) == uint8('{'));" >"$out/split.log" 2>&1 ||
  { echo "vlab_split_datagrams FAILED"; cat "$out/split.log"; exit 1; }

# run NAME DURATION PERIODS CALL EXPECTED: vlab serve for DURATION s, the Octave CALL
# (PORT in it replaced by the arm's port) against it; both must exit 0, the Octave log
# must hold EXPECTED, and the run's summary the PERIODS periods, each one's command
# accepted
run() {
  local name="$1" duration="$2" periods="$3" call="$4" expected="$5" port="" serve
  "$vlab" serve scenes/pa10_serve --duration "$duration" -q --port pa10=0 --port jr3=0 --port sim=0 \
    --out "$out/$name" >"$out/$name.serve.log" 2>&1 &
  serve=$!
  for _ in $(seq 200); do
    port=$(grep -o -m1 "pa10 (arm) 127.0.0.1:[0-9]*" "$out/$name.serve.log" 2>/dev/null | grep -o "[0-9]*$")
    [ -n "$port" ] && break
    sleep 0.05
  done
  [ -n "$port" ] || { echo "$name: vlab serve did not start"; cat "$out/$name.serve.log"; kill "$serve"; exit 1; }
  octave_eval "${call//PORT/$port}" >"$out/$name.octave.log" 2>&1
  local octave_status=$?
  wait "$serve"; local serve_status=$?
  cat "$out/$name.octave.log" "$out/$name.serve.log"
  [ "$octave_status" -eq 0 ] || { echo "$name: octave exited $octave_status"; exit 1; }
  [ "$serve_status" -eq 0 ] || { echo "$name: vlab serve exited $serve_status"; exit 1; }
  grep -qF "$expected" "$out/$name.octave.log" || { echo "$name: no '$expected' in the Octave log"; exit 1; }
  python3 - "$out/$name/summary.json" "$periods" <<'PY' || exit 1
import json, sys
s, periods = json.load(open(sys.argv[1])), int(sys.argv[2])
arm = next(d for d in s["bridge"]["devices"] if d["name"] == "pa10")
assert s["result"] == "pass", s["failure"]
assert s["clock_stats"] == {"name": "lockstep", "periods": periods, "timeouts": 0}, s["clock_stats"]
assert arm["accepted"] == periods and arm["refused"] == 0, arm
assert arm["stale"] == 0 and arm["duplicate"] == 0, arm
PY
  echo "$name: $periods lockstep periods answered, every command accepted"
}

run hold 2 1000 "vlab_arm_hold('127.0.0.1', PORT, 1000)" "answered 1000 states (seq 0 to 999), skipped 0, on watchdog hold 0,"
run simulink 0.2 100 "vlab_simulink_loop('127.0.0.1', PORT, 100)" "answered 100 states, the last seq 99"

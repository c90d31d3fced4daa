#!/usr/bin/env bash
# scenes/hoap3_stand through `vlab serve` (lockstep, free loopback ports) with the
# external controller examples/hoap3_stand, shortened: --stand 1 moves the squat to
# 1-6 s and the wave to 7-12 s, and the run lasts DURATION (13 s) instead of 42 s.
# Passes when the server's checks pass (FSR sum within 2 % of m g, CoP inside the
# support polygon, servo tracking, joint limits, upright), the controller exits 0
# once the run is over, the squat and the wave really happened (log.csv), and a
# controller that gets SIGTERM exits 0 too.
#   hoap3_serve_test.sh BUILD_DIR OUT_DIR [DURATION]
set -u
build="$1"; out="$2"; duration="${3:-13}"
rm -rf "$out"; mkdir -p "$out"
fail=0
ports="--port hoap3=0 --port feet=0 --port imu=0 --port sim=0 --port right_eye=0 --port left_eye=0"

# start_server NAME CLOCK DURATION: vlab serve in the background; sets $server_pid,
# $arm and $feet (ADDRESS:PORT, parsed from its start line)
start_server() {
  # shellcheck disable=SC2086
  "$build/vlab" serve scenes/hoap3_stand --clock "$2" --duration "$3" $ports -q --out "$out/$1" \
    >"$out/$1.server.log" 2>&1 &
  server_pid=$!
  for _ in $(seq 400); do
    arm=$(grep -o -m1 "hoap3 (arm) 127.0.0.1:[0-9]*" "$out/$1.server.log" 2>/dev/null | grep -o "127.0.0.1:[0-9]*")
    feet=$(grep -o -m1 "feet (feet) 127.0.0.1:[0-9]*" "$out/$1.server.log" 2>/dev/null | grep -o "127.0.0.1:[0-9]*")
    [ -n "$arm" ] && [ -n "$feet" ] && return 0
    sleep 0.05
  done
  echo "$1: server did not start"; cat "$out/$1.server.log"; return 1
}

# 1. the shortened scenario, to its end
if start_server run lockstep "$duration"; then
  if timeout 300 "$build/examples/hoap3_stand" --arm "$arm" --feet "$feet" --stand 1 --max-error 0.06 \
       >"$out/run.controller.log" 2>&1; then
    echo "controller: $(grep "^max tracking error" "$out/run.controller.log"); $(grep "^FSR sum" "$out/run.controller.log")"
  else
    echo "controller FAILED"; cat "$out/run.controller.log"; fail=1
  fi
  if wait "$server_pid"; then tail -1 "$out/run.server.log"; else echo "server FAILED"; cat "$out/run.server.log"; fail=1; fi
else
  fail=1
fi
[ -f "$out/run/summary.json" ] && python3 - "$out/run" <<'PY' || fail=1
import csv, json, math, sys
run = sys.argv[1]
s = json.load(open(f"{run}/summary.json"))
for c in s["checks"]:
    print(f"  check {c['name']}: {c['value']} ({'pass' if c['pass'] else 'FAIL'})")
assert s["result"] == "pass", s["failure"]
arm = next(d for d in s["bridge"]["devices"] if d["name"] == "hoap3")
assert arm["refused"] == 0 and arm["accepted"] >= 0.99 * s["duration_s"] / s["control_period_s"], arm
rows = list(csv.DictReader(open(f"{run}/log.csv")))
col = lambda name, t0, t1: [float(r[name]) for r in rows if t0 <= float(r["time"]) <= t1]
knee = max(col("hoap3.q.RL_J4", 3.0, 4.0))          # squat bottom: 0.4 + 0.8 rad commanded
elbow = col("hoap3.q.RA_J4", 8.5, 10.5)              # elbow waving +-0.4 rad about 1.1 rad
end = col("hoap3.q.RL_J4", 12.5, 13.0)               # standing again: 0.4 rad commanded
print(f"  squat knee {knee:.3f} rad, wave elbow {min(elbow):.3f}..{max(elbow):.3f} rad, final knee {end[-1]:.3f} rad")
assert knee > 1.1, "no squat"
assert max(elbow) - min(elbow) > 0.6, "no wave"
assert abs(end[-1] - 0.4) < 0.1, "not standing at the end"
PY

# 2. SIGTERM: the controller ends cleanly (exit 0) while the run goes on (realtime:
# lockstep would be over before the signal)
if start_server term realtime 30; then
  "$build/examples/hoap3_stand" --arm "$arm" --stand 1 >"$out/term.controller.log" 2>&1 &
  controller_pid=$!
  # the signal comes inside its control loop: once it has printed its first phase (the squat,
  # 1 s into the run; 30 s at most)
  for _ in $(seq 600); do grep -q ": squat;" "$out/term.controller.log" && break; sleep 0.05; done
  grep -q ": squat;" "$out/term.controller.log" || { echo "SIGTERM: the controller never reached its squat"; fail=1; }
  kill -TERM "$controller_pid"
  if wait "$controller_pid"; then
    echo "SIGTERM: controller exit 0: $(tail -1 "$out/term.controller.log")"
  else
    echo "SIGTERM: controller FAILED"; cat "$out/term.controller.log"; fail=1
  fi
  kill -INT "$server_pid"; wait "$server_pid"
else
  fail=1
fi
exit $fail

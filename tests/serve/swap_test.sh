#!/usr/bin/env bash
# The three-way swap: the same controller binary, unchanged, drives
#   (a) vlab serve in lockstep, (b) vlab serve in realtime, (c) vlab-kinsim;
# the Python example does the same. Every run must pass its tracking bound,
# and the served runs must pass their scenario's checks.
#   swap_test.sh BUILD_DIR OUT_DIR
#
# The paced runs (b, c) run at realtime priority where permitted, as a controller of the real
# arm runs and as the realtime case studies do (docs/scenarios.md, "Realtime priority"): the
# server's control thread at SCHED_FIFO 50 (vlab serve --rt-priority 50; vlab-kinsim under
# chrt), the controller at 40 (chrt). Where it is refused they run at normal priority and the
# test says so. At normal priority beside three busy loops on 2 cores a served run lost 28-280
# of its 3250 commands and the watchdog held the arm up to 4 times; at priority it took
# 3249-3250 with no hold (docs/testing.md, "Side by side").
set -u
build="$1"; out="$2"
rm -rf "$out"; mkdir -p "$out"
fail=0
if chrt -f 40 true 2>/dev/null; then
  controller_rt=(chrt -f 40); server_rt=(chrt -f 50); serve_rt=(--rt-priority 50)
  echo "paced runs at realtime priority: servers SCHED_FIFO 50, controllers 40"
else
  controller_rt=(); server_rt=(); serve_rt=()
  echo "paced runs at normal priority: realtime priority is not permitted here (chrt -f 40 refused)"
fi

# start_server NAME COMMAND...: runs it in the background, waits for its start
# line, sets $server_pid and $port (parsed from "... 127.0.0.1:PORT")
start_server() {
  local name="$1"; shift
  "$@" >"$out/$name.server.log" 2>&1 &
  server_pid=$!
  port=""
  for _ in $(seq 200); do
    port=$(grep -o -m1 "pa10 (arm) 127.0.0.1:[0-9]*\|on 127.0.0.1:[0-9]*" "$out/$name.server.log" 2>/dev/null \
           | grep -o "[0-9]*$")
    [ -n "$port" ] && return 0
    sleep 0.05
  done
  echo "$name: server did not start"; cat "$out/$name.server.log"; return 1
}

# run NAME CONTROLLER... : one controller against one server, then the server's exit code
run() {
  local name="$1" server_kind="$2"; shift 2
  case "$server_kind" in
    lockstep|realtime)
      local rt=()
      if [ "$server_kind" = realtime ]; then rt=("${serve_rt[@]}"); fi
      start_server "$name" "$build/vlab" serve scenes/pa10_serve --clock "$server_kind" -q "${rt[@]}" \
        --port pa10=0 --port jr3=0 --port sim=0 --out "$out/$name" || { fail=1; return; } ;;
    kinsim)
      start_server "$name" "${server_rt[@]}" "$build/vlab-kinsim" --port 0 --duration 12 || { fail=1; return; } ;;
  esac
  local priority=()
  if [ "$server_kind" != lockstep ]; then priority=("${controller_rt[@]}"); fi
  if timeout 60 "${priority[@]}" "$@" --arm "127.0.0.1:$port" --max-error 0.01 >"$out/$name.controller.log" 2>&1; then
    echo "$name: $(tail -1 "$out/$name.controller.log")"
  else
    echo "$name: controller FAILED"; cat "$out/$name.controller.log"; fail=1
  fi
  if [ "$server_kind" = kinsim ]; then kill -INT "$server_pid"; fi
  if ! wait "$server_pid"; then echo "$name: server FAILED"; cat "$out/$name.server.log"; fail=1; fi
}

for kind in lockstep realtime kinsim; do
  run "cpp_$kind" "$kind" "$build/examples/joint_control"
  run "python_$kind" "$kind" python3 examples/joint_control.py
done
# the served runs' own checks passed too (their exit code was 0), and the arm took every command
python3 - "$out" <<'PY' || fail=1
import json, sys
for name in ("cpp_lockstep", "cpp_realtime", "python_lockstep", "python_realtime"):
    s = json.load(open(f"{sys.argv[1]}/{name}/summary.json"))
    arm = next(d for d in s["bridge"]["devices"] if d["name"] == "pa10")
    line = f"{name}: clock {s['clock']}, accepted {arm['accepted']}, refused {arm['refused']}"
    if s["clock"] == "realtime":  # what the paced run got: its priority, its deadlines, the watchdog
        clock, lab = s["clock_stats"], s["realtime_priority"]["lab"]
        line += (f", watchdog holds {arm['watchdog_holds']}, missed deadlines {clock['missed_deadlines']}"
                 f" of {clock['periods']} (worst {clock['lateness_s']['max'] * 1e3:.1f} ms),"
                 f" {'SCHED_FIFO %d' % lab['requested'] if lab['granted'] else 'normal priority'}")
    print(line)
    assert s["result"] == "pass", (name, s["failure"])
    assert arm["accepted"] > 2000 and arm["refused"] == 0, (name, arm)
PY
exit $fail

#!/usr/bin/env bash
# scenes/pa10_nomad_reach through `vlab serve` (lockstep, free loopback ports), with
# the external controller examples/nomad_reach started by hand, as a user would:
# the same program `vlab run` starts for that scenario. Passes when the server's
# checks pass (tool held on the base while driving, base parked, tool at the
# target), every period's command was accepted from both devices, and the
# controller exits 0 once the run is over.
#   nomad_reach_serve_test.sh BUILD_DIR OUT_DIR
set -u
build="$1"; out="$2"
rm -rf "$out"; mkdir -p "$out"
"$build/vlab" serve scenes/pa10_nomad_reach --port pa10=0 --port nomad=0 -q --out "$out/run" \
  >"$out/server.log" 2>&1 &
server_pid=$!
arm=""; base=""
for _ in $(seq 400); do
  arm=$(grep -o -m1 "pa10 (arm) 127.0.0.1:[0-9]*" "$out/server.log" 2>/dev/null | grep -o "127.0.0.1:[0-9]*")
  base=$(grep -o -m1 "nomad (base) 127.0.0.1:[0-9]*" "$out/server.log" 2>/dev/null | grep -o "127.0.0.1:[0-9]*")
  [ -n "$arm" ] && [ -n "$base" ] && break
  sleep 0.05
done
if [ -z "$arm" ] || [ -z "$base" ]; then echo "server did not start"; cat "$out/server.log"; kill "$server_pid"; exit 1; fi
fail=0
if timeout 120 "$build/examples/nomad_reach" --scene scenes/pa10_nomad.xml --arm "$arm" --base "$base" \
     >"$out/controller.log" 2>&1; then
  echo "controller: $(tail -1 "$out/controller.log")"
else
  echo "controller FAILED"; cat "$out/controller.log"; fail=1
fi
if wait "$server_pid"; then tail -1 "$out/server.log"; else echo "server FAILED"; cat "$out/server.log"; fail=1; fi
[ -f "$out/run/summary.json" ] && python3 - "$out/run" <<'PY' || fail=1
import json, sys
s = json.load(open(f"{sys.argv[1]}/summary.json"))
for c in s["checks"]:
    print(f"  check {c['name']}: {c['value']} ({'pass' if c['pass'] else 'FAIL'})")
assert s["result"] == "pass", s["failure"]
periods = round(s["duration_s"] / s["control_period_s"])
for d in s["bridge"]["devices"]:
    assert d["refused"] == 0 and d["accepted"] == periods, d
PY
[ -f "$out/run/summary.json" ] || fail=1
[ "$fail" = 0 ] && echo "nomad_reach through vlab serve: pass"
exit "$fail"

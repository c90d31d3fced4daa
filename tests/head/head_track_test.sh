#!/usr/bin/env bash
# The head follows the ball through vlab serve: scenes/head_track in lockstep, shortened
# to 5 s, with examples/head_track started by hand as the external controller, twice.
# Each run must pass the scenario's checks (both eyes' gaze error after 1 s, the ball
# visible to both eyes throughout, joint limits); the controller must exit 0 having found
# the ball in every frame it used, with no frame late; and the two runs' log.csv must be
# identical byte for byte (lockstep is repeatable with cameras in the loop).
#   head_track_test.sh BUILD_DIR OUT_DIR
set -u
build="$1"; out="$2"
rm -rf "$out"; mkdir -p "$out"
fail=0

# run NAME: one served run and one controller; sets fail=1 on any failure
run() {
  local name="$1" line="" server
  "$build/vlab" serve scenes/head_track --duration 5 -q --port head=0 --port left_eye=0 --port right_eye=0 \
    --out "$out/$name" >"$out/$name.server.log" 2>&1 &
  server=$!
  for _ in $(seq 400); do
    line=$(grep -m1 "^vlab serve: .*right_eye (camera)" "$out/$name.server.log" 2>/dev/null)
    [ -n "$line" ] && break
    sleep 0.05
  done
  if [ -z "$line" ]; then
    echo "$name: server did not start"; cat "$out/$name.server.log"; kill "$server" 2>/dev/null; fail=1; return
  fi
  endpoint() { echo "$line" | grep -o "$1 ([a-z]*) [0-9.]*:[0-9]*" | grep -o "[0-9.]*:[0-9]*$"; }
  if timeout 120 "$build/examples/head_track" --arm "$(endpoint head)" --left "$(endpoint left_eye)" \
       --right "$(endpoint right_eye)" >"$out/$name.controller.log" 2>&1; then
    sed "s/^/$name: /" "$out/$name.controller.log"
  else
    echo "$name: controller FAILED"; cat "$out/$name.controller.log"; fail=1
  fi
  if ! wait "$server"; then echo "$name: server FAILED"; cat "$out/$name.server.log"; fail=1; fi
  # each eye reported once: it used frames, every one showed the ball, none came late
  local eye
  for eye in left right; do
    if [ "$(grep -cE "^$eye eye: ([1-9][0-9]*) frames, ball in \1, late 0," "$out/$name.controller.log")" != 1 ]; then
      echo "$name: no '$eye eye:' line with every frame showing the ball and none late"; fail=1
    fi
  done
}

run first
run second
python3 - "$out" <<'PY' || fail=1
import json, sys
for name in ("first", "second"):
    s = json.load(open(f"{sys.argv[1]}/{name}/summary.json"))
    figures = ", ".join(f"{c['name']} {c['value']:.4g}" for c in s["checks"])
    print(f"{name}: {s['result']}; {figures}")
    assert s["result"] == "pass", (name, s["failure"])
    assert len(s["checks"]) == 5, s["checks"]
PY
if cmp -s "$out/first/log.csv" "$out/second/log.csv"; then
  echo "log.csv: identical in both runs"
else
  echo "log.csv: the two lockstep runs DIFFER"; fail=1
fi
exit $fail

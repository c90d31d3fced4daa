#!/usr/bin/env bash
# Yo-yo stage 3 on a busy machine: runs cases/yoyo/stage3 N times (default 10) while
# two CPU-bound processes, started and stopped here at normal priority, keep both cores
# busy. Each run is the full stage (46 s of wall-clock time) at the scenario's realtime
# priority (granted to root, CAP_SYS_NICE or an rtprio limit; summary.json says what it
# got). Prints per run the verdict, the priority granted, missed deadlines, the worst
# period-start lateness and the swing check, then the steal time, the worst period's cause and the
# newest command's age (summary.json's clock_stats.stall, bridge.command_age_s); then "passed K of N". Exit 0 when all passed.
# --io adds a third process doing file I/O in OUT/io (each round: 200 MB written and fsynced, read
# back, 200 small files written and fsynced, then removed).
#   cases/yoyo/tests/stage3_under_load.sh [--io] [N] [VLAB] [OUT]
set -euo pipefail
io=0
if [ "${1:-}" = "--io" ]; then io=1; shift; fi
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
top="$(cd "$here/../../.." && pwd)"
runs="${1:-10}"
vlab="${2:-$top/build/vlab}"
out="${3:-$(mktemp -d)}"
[ -x "$vlab" ] || { echo "stage3_under_load: no vlab at $vlab (build first)" >&2; exit 2; }
mkdir -p "$out"

hogs=()
stop_hogs() { for p in "${hogs[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; }
trap stop_hogs EXIT
for _ in 1 2; do
  ( while :; do :; done ) &
  hogs+=("$!")
done
if [ "$io" -eq 1 ]; then
  mkdir -p "$out/io"
  (
    while :; do
      dd if=/dev/zero of="$out/io/big" bs=1M count=200 conv=fsync status=none
      cat "$out/io/big" >/dev/null
      for k in $(seq 1 200); do dd if=/dev/zero of="$out/io/small$k" bs=4k count=4 conv=fsync status=none; done
      rm -f "$out/io/big" "$out/io"/small*
    done
  ) &
  hogs+=("$!")
fi
load="two CPU-bound processes"
[ "$io" -eq 0 ] || load="$load and a file-I/O process"

passed=0
for i in $(seq 1 "$runs"); do
  dir="$out/run$i"
  rc=0
  "$vlab" run "$top/cases/yoyo/stage3.yaml" --quiet --out "$dir" >/dev/null 2>"$dir.err" || rc=$?
  [ "$rc" -eq 0 ] && passed=$((passed + 1))
  python3 - "$dir/summary.json" "$i" "$rc" <<'EOF'
import json, sys
path, i, rc = sys.argv[1], sys.argv[2], int(sys.argv[3])
try:
    s = json.load(open(path))
except OSError:
    print(f"run {i}: exit {rc}, no summary.json")
    sys.exit(0)
c = s["clock_stats"]
rt = s.get("realtime_priority", {})
lab = rt.get("lab", {})
ctl = rt.get("controller", {})
swing = next((k for k in s["checks"] if k["name"] == "every_swing_reaches_the_level"), None)
print(f"run {i}: {s['result']}; priority lab {lab.get('requested')} {'granted' if lab.get('granted') else 'not granted'}, "
      f"controller {ctl.get('requested')} {'granted' if ctl.get('granted') else 'not granted'}; "
      f"missed {c.get('missed_deadlines')} of {c.get('periods')}, lateness max {c['lateness_s']['max'] * 1e3:.2f} ms; "
      f"lowest swing top {swing['value']:.4f} m (>= {swing['bound']['min']})" if swing else "")
stall = c.get("stall")
if stall:
    w = stall["worst_period"]
    steal = stall.get("steal_fraction")
    print(f"  steal {steal * 100:.2f} % of the CPUs' time" if steal is not None else "  steal unknown",
          f"; worst period {w['period']} ({w['lateness_s'] * 1e3:.2f} ms late): {w['cause']}", sep="")
ages = s.get("bridge", {}).get("command_age_s")
if ages and ages.get("count"):
    print(f"  newest command's age at a period start: p99 {ages['p99'] * 1e3:.2f} ms, max {ages['max'] * 1e3:.2f} ms")
EOF
done
echo "passed $passed of $runs ($load beside every run; output in $out)"
[ "$passed" -eq "$runs" ]

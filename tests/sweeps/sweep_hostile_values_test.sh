#!/bin/bash
# A sweep file whose values hold every byte 0x01-0x1f and 0x7f, quotes, $(...),
# backquotes and planted commands ("\ntouch CANARY"), listed with vlab sweep --list
# and run through GNU parallel (the documented recipe) and through
# tools/vlab_sweep_array.sh (the Slurm recipe's awk and parallel, as array tasks 0
# and 1 of 2): every job line is one line of printable characters, every value
# arrives in vlab intact (the scenario's description, read back from each run's
# summary.json, equals the sweep file's value byte for byte), and no canary file
# appears. The scenario is a falling ball for 0.05 s, so the 39 runs take seconds.
# usage: sweep_hostile_values_test.sh VLAB SOURCE_DIR
set -u
vlab=$1
src=$2
for tool in parallel python3; do
  command -v "$tool" >/dev/null || { echo "FAIL: missing $tool (tools/setup.sh installs parallel)"; exit 1; }
done
work=$(mktemp -d /tmp/vlab-sweep-hostile-XXXXXX)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
printf '%s\n' "<mujoco><worldbody><body pos='0 0 1'><freejoint/><geom size='0.1'/></body></worldbody></mujoco>" >ball.xml
printf '%s\n' 'scene: ball.xml' 'duration: 0.05' 'control_period: 0.01' \
  'checks:' '  - {name: ran, signal: time, reduce: final, min: 0}' >tiny.yaml
# the values, and the sweep file that holds them in YAML double quotes (\xHH escapes)
WORK="$work" python3 - <<'PY' || { echo "FAIL: could not write the sweep file"; exit 1; }
import json, os
work = os.environ["WORK"]
values = ["a" + chr(c) + "b" for c in list(range(1, 0x20)) + [0x7f]]
values += ["x\ntouch CANARY\n", "\ntouch " + work + "/CANARY_ABS", "$(touch " + work + "/CANARY_SUB)",
           "`touch " + work + "/CANARY_BQ`", "'; touch " + work + "/CANARY_Q; '", "\"double\" 'single' \\ \\n",
           "\r\x1b[2K"]
def quoted(s):
    out = '"'
    for ch in s:
        if ch in '"\\': out += "\\" + ch
        elif ord(ch) < 0x20 or ord(ch) == 0x7f: out += "\\x%02x" % ord(ch)
        else: out += ch
    return out + '"'
with open("expected.json", "w") as f: json.dump(values, f)
with open("hostile.yaml", "w") as f:
    f.write("name: hostile\nscenario: tiny.yaml\ngrid:\n  description:\n")
    for v in values: f.write("    - " + quoted(v) + "\n")
PY
n=$(python3 -c 'import json; print(len(json.load(open("expected.json"))))')

# every job line one line, printable (bytes 0x20-0x7e), n lines
check_list() {
  python3 - "$1" "$n" <<'PY'
import sys
data = open(sys.argv[1], "rb").read()
lines = data.split(b"\n")
assert lines[-1] == b"", "the list does not end with a newline"
bad = [l for l in lines[:-1] if any(b < 0x20 or b == 0x7f for b in l)]
if len(lines) - 1 != int(sys.argv[2]) or bad:
    print("FAIL: %d job lines for %s runs, %d with control characters" % (len(lines) - 1, sys.argv[2], len(bad)))
    sys.exit(1)
PY
}
# every run's summary.json holds its value as description, byte for byte
check_runs() {
  python3 - "$1" "$2" <<'PY'
import json, sys
values = json.load(open("expected.json"))
bad = []
for i, v in enumerate(values):
    try:
        s = json.load(open("%s/p%02d/summary.json" % (sys.argv[1], i)))
        got = s["description"]
    except Exception as e:
        got = "<%s>" % e
    if got != v: bad.append("p%02d: %r != %r" % (i, got, v))
if bad:
    print("FAIL: %s: %d of %d values did not arrive intact:\n  %s" % (sys.argv[2], len(bad), len(values), "\n  ".join(bad)))
    sys.exit(1)
print("%s: %d of %d values arrived intact" % (sys.argv[2], len(values), len(values)))
PY
}
fail=0
"$vlab" sweep hostile.yaml --list --out "$work/parallel" >jobs.txt || { echo "FAIL: vlab sweep --list"; exit 1; }
check_list jobs.txt || fail=1
parallel --will-cite -j 2 --joblog parallel.log <jobs.txt >parallel.out 2>&1 || { echo "FAIL: parallel:"; cat parallel.log; fail=1; }
check_runs "$work/parallel" "GNU parallel" || fail=1

"$vlab" sweep hostile.yaml --list --out "$work/array" >array_jobs.txt || { echo "FAIL: vlab sweep --list"; exit 1; }
check_list array_jobs.txt || fail=1
for task in 0 1; do
  SLURM_ARRAY_TASK_COUNT=2 SLURM_ARRAY_TASK_ID=$task SLURM_CPUS_PER_TASK=2 "$src/tools/vlab_sweep_array.sh" array_jobs.txt \
    >"array_$task.out" 2>&1 || { echo "FAIL: array task $task:"; cat "array_$task.out"; fail=1; }
done
check_runs "$work/array" "the Slurm array script" || fail=1

canaries=$(ls "$work" | grep CANARY)
[ -z "$canaries" ] || { echo "FAIL: a value ran as a command: $canaries"; fail=1; }
[ $fail -eq 0 ] && echo "hostile values: every value intact, no canary"
exit $fail

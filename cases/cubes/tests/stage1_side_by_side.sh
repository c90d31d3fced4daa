#!/usr/bin/env bash
# Run as: stage1_side_by_side.sh VLAB CASE OUT PYTHON
# Stage 1 as shipped (seed 1: the scenario's own test, which tests/scenarios leaves to this one)
# and with seed 2, at the same time, as `vlab sweep -j 2` over seeds runs them: each must pass its
# checks, and each must have served its devices and run its vision program on ports of its own
# (the run chooses them: {port:vision} in stage1.yaml), read back from the two summary.json.
set -u
if [ $# -ne 4 ]; then
  echo "usage: stage1_side_by_side.sh VLAB CASE OUT PYTHON" >&2
  exit 2
fi
vlab=$1 case=$2 out=$3 python=$4
rm -rf "$out"
mkdir -p "$out"
pids=()
for seed in 1 2; do
  # seed 1 is the scenario's own: run unchanged, without --seed
  seed_option=()
  [ $seed -eq 1 ] || seed_option=(--seed $seed)
  # 280 s each: a run takes about 12 s of wall time alone (cases/cubes/tests/CMakeLists.txt)
  timeout 280 "$vlab" run "$case/stage1.yaml" "${seed_option[@]}" --quiet --out "$out/seed$seed" \
    >"$out/seed$seed.txt" 2>&1 &
  pids+=($!)
done
status=0
for i in 0 1; do
  seed=$((i + 1))
  wait "${pids[$i]}"
  rc=$?
  if [ $rc -eq 0 ]; then
    echo "stage 1, seed $seed: pass ($(tail -n 1 "$out/seed$seed.txt"))"
  else
    echo "stage 1, seed $seed: vlab run exit $rc:"
    cat "$out/seed$seed.txt"
    status=1
  fi
done
[ $status -eq 0 ] || exit $status
# the ports each run took: its served devices' and its vision program's, none shared
"$python" - "$out/seed1/summary.json" "$out/seed2/summary.json" <<'PY' || exit 1
import json, sys
taken = []
for path in sys.argv[1:]:
    s = json.load(open(path))
    ports = [d["port"] for d in s["bridge"]["devices"]] + [s["controller"]["ports"]["vision"]]
    print("%s: ports %s (vision %d)" % (path, sorted(ports), s["controller"]["ports"]["vision"]))
    taken += ports
if len(set(taken)) != len(taken) or 0 in taken:
    sys.exit("the two runs shared a port, or one had none: %s" % taken)
PY

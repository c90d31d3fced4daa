#!/usr/bin/env bash
# Run as: seeds.sh VLAB CASE OUT
# The handover on seeds 1-10 (seeds.yaml), two runs at a time (vlab sweep -j 2), from scratch
# (a sweep skips runs whose record is current, and the record does not cover the scene or the
# programs): every run must pass its checks, and the results table must hold ten passing rows.
set -u
if [ $# -ne 3 ]; then
  echo "usage: seeds.sh VLAB CASE OUT" >&2
  exit 2
fi
vlab=$1 case=$2 out=$3
rm -rf "$out"
start=$(date +%s%N)
"$vlab" sweep "$case/tests/seeds.yaml" -j 2 --out "$out"
rc=$?
end=$(date +%s%N)
echo "handover seeds: sweep exit $rc, $(((end - start) / 1000000)) ms of wall time for 10 runs"
[ $rc -eq 0 ] || exit 1
table=$("$vlab" collect "$out" --no-timings 2>/dev/null)
passed=$(printf '%s\n' "$table" | awk -F, 'NR > 1 && $5 == "pass"' | wc -l)
echo "handover seeds: $passed of 10 runs pass"
[ "$passed" -eq 10 ] || { printf '%s\n' "$table"; exit 1; }

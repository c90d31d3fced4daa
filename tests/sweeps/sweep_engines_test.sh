#!/bin/bash
# The 3-seed x 3-gain sweep scenes/sweeps/pa10_gains.yaml run three ways, with equal
# collected tables (timings left out):
#   1. vlab sweep -j 2 (local);
#   2. vlab sweep --list | GNU parallel -j 2 (the documented local recipe);
#   3. a Slurm array job of 3 tasks (tools/vlab_sweep_array.sh) on a single-node Slurm that
#      this test brings up in a temporary folder (munged, slurmctld, slurmd) and tears down.
# Missing tools fail the test with a message (tools/setup.sh installs them); no skip.
# usage: sweep_engines_test.sh VLAB SOURCE_DIR
set -u
vlab=$1
src=$2
missing=""
for tool in parallel munged slurmctld slurmd sbatch sinfo python3; do
  command -v "$tool" >/dev/null || missing="$missing $tool"
done
if [ -n "$missing" ]; then
  echo "FAIL: missing$missing: install the Debian packages parallel slurm-wlm munge (tools/setup.sh, VLAB_TEST_APT_PACKAGES)"
  exit 1
fi
work=$(mktemp -d /tmp/vlab-sweep-engines-XXXXXX)
SLURM_DIR="$work/slurm"
. "$src/tests/sweeps/slurm_single_node.sh"
trap 'slurm_down; rm -rf "$work"' EXIT
sweep="$src/scenes/sweeps/pa10_gains.yaml"
fail=0

# 1. local
"$vlab" sweep "$sweep" -j 2 --out "$work/local" >"$work/local.txt" || { cat "$work/local.txt"; echo "FAIL: local sweep"; exit 1; }
"$vlab" collect "$work/local" --no-timings -o "$work/local.csv" || exit 1
[ "$(wc -l < "$work/local.csv")" -eq 10 ] || { echo "FAIL: local table is not a header and 9 runs:"; cat "$work/local.csv"; exit 1; }

# 2. GNU parallel, from the job list
"$vlab" sweep "$sweep" --list --out "$work/parallel" >"$work/parallel_jobs.txt" || exit 1
parallel --will-cite -j 2 --joblog "$work/parallel.log" <"$work/parallel_jobs.txt" || { echo "FAIL: parallel: $(cat "$work/parallel.log")"; fail=1; }
"$vlab" collect "$work/parallel" --no-timings -o "$work/parallel.csv" || exit 1
if cmp -s "$work/local.csv" "$work/parallel.csv"; then
  echo "GNU parallel: collected table equals the local one (9 runs)"
else
  echo "FAIL: GNU parallel's table differs from the local one:"; diff "$work/local.csv" "$work/parallel.csv"; fail=1
fi

# 3. Slurm: a 3-task array job over the same list
slurm_up || { echo "FAIL: could not bring up the single-node Slurm"; exit 1; }
"$vlab" sweep "$sweep" --list --out "$work/slurm_runs" >"$work/slurm_jobs.txt" || exit 1
sbatch --wait --array=0-2 --cpus-per-task=1 -o "$work/slurm-%a.txt" "$src/tools/vlab_sweep_array.sh" "$work/slurm_jobs.txt" \
  || { echo "FAIL: the array job failed:"; cat "$work"/slurm-*.txt; fail=1; }
"$vlab" collect "$work/slurm_runs" --no-timings -o "$work/slurm.csv" || exit 1
if cmp -s "$work/local.csv" "$work/slurm.csv"; then
  echo "Slurm array job: collected table equals the local one (9 runs)"
else
  echo "FAIL: the Slurm table differs from the local one:"; diff "$work/local.csv" "$work/slurm.csv"; fail=1
fi
exit $fail

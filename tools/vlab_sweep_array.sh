#!/bin/bash
# A Slurm array task that runs its share of a vlab job list (vlab sweep SWEEP.yaml --list).
#
#   build/vlab sweep SWEEP.yaml --list --out /shared/sweeps/NAME > jobs.txt
#   sbatch --array=0-7 --cpus-per-task=16 tools/vlab_sweep_array.sh jobs.txt
#
# Task i of K runs lines i+1, i+1+K, i+1+2K, ... of the list, with GNU parallel over the
# CPUs Slurm gave it (--cpus-per-task; one at a time without it), since runs are short
# and sites ask for few allocations. Every line is a whole `vlab run` command writing
# its own output folder, so the tasks share nothing but the (shared) file system.
# Exit status: 0 when every run of this task exited 0, else the number that did not.
set -u
jobs=${1:?usage: sbatch --array=0-N tools/vlab_sweep_array.sh JOBS.txt}
count=${SLURM_ARRAY_TASK_COUNT:-1}
index=${SLURM_ARRAY_TASK_ID:-0}
cpus=${SLURM_CPUS_PER_TASK:-1}
[ -r "$jobs" ] || { echo "vlab_sweep_array: cannot read job list '$jobs'" >&2; exit 2; }
command -v parallel >/dev/null || { echo "vlab_sweep_array: GNU parallel is not installed" >&2; exit 2; }
awk -v k="$count" -v i="$index" '(NR - 1) % k == i' "$jobs" | parallel --will-cite -j "$cpus"

#!/usr/bin/env bash
# vlab quick start: install what is missing, build, run a scenario headless.
#   ./run.sh [SCENARIO] [vlab run options]
# Default: cases/yoyo/stage1, the yo-yo case study's first stage (the PA10 keeps a yo-yo
# swinging to a set height, lockstep); its plot is out/yoyo_stage1/yoyo.png.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
source tools/setup.sh
vlab_setup
if [ $# -gt 0 ]; then
  scenario=$1
  shift
  exec build/vlab run "$scenario" "$@"
fi
status=0
build/vlab run cases/yoyo/stage1 || status=$?
if [ -f out/yoyo_stage1/yoyo.png ]; then
  grep -h "amplitude check" out/yoyo_stage1/controller.log || true
  echo "Open out/yoyo_stage1/yoyo.png: the hand's and the yo-yo's height against time (numbers in"
  echo "out/yoyo_stage1/yoyo.csv; how to read it: cases/yoyo/README.md). The other stages:"
  echo "./run.sh cases/yoyo/stage2, ./run.sh cases/yoyo/stage3."
fi
exit $status

#!/usr/bin/env bash
# vlab quick start: install what is missing, build, run a scenario headless.
#   ./run.sh [SCENARIO] [vlab run options]     (default scenario: scenes/pa10_reach)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
source tools/setup.sh
vlab_setup
scenario="${1:-scenes/pa10_reach}"
[ $# -gt 0 ] && shift
exec build/vlab run "$scenario" "$@"

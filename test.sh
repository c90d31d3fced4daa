#!/usr/bin/env bash
# vlab test suite: install what is missing, build, run every test through ctest.
#   ./test.sh [ctest options]      e.g. ./test.sh -R physics
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
source tools/setup.sh
vlab_setup --tests
cd build
exec ctest --output-on-failure -j "$(nproc)" "$@"

#!/usr/bin/env bash
# vlab test suite: install what is missing, build (build/ as ./run.sh builds it, so after
# ./run.sh nothing is compiled again), build the packet fuzzer (clang, build/fuzz), run every
# test through ctest. With VLAB_WERROR=1, build/ is configured with -Werror first (any compiler
# warning fails the build). With VLAB_SANITIZE=1, then the sanitizer lane (tools/sanitize.sh:
# the unit tests under AddressSanitizer + UndefinedBehaviorSanitizer, in build-asan/).
# .ci/run sets both.
#   ./test.sh [ctest options]      e.g. ./test.sh -R physics
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
source tools/setup.sh
vlab_setup --tests
status=0
(cd build && ctest --output-on-failure -j "$(nproc)" "$@") || status=$?
if [ "${VLAB_SANITIZE:-0}" = 1 ]; then
  tools/sanitize.sh || status=$?
fi
exit $status

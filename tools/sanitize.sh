#!/usr/bin/env bash
# The sanitizer lane: the libraries and the unit tests that start no program of the build
# (CMake target vlab_unit_tests, tests/CMakeLists.txt), built with AddressSanitizer and
# UndefinedBehaviorSanitizer into build-asan/, then `ctest -L unit` there. Any sanitizer
# report fails its test. Run from anywhere; ./test.sh runs it when VLAB_SANITIZE=1.
#   tools/sanitize.sh [ctest options]      e.g. tools/sanitize.sh -R CsvLogTest
# Environment: VLAB_ASAN_BUILD (default build-asan) is the build folder.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
build="${VLAB_ASAN_BUILD:-build-asan}"
case "$build" in /*) ;; *) build="$PWD/$build" ;; esac
jobs="$(nproc 2>/dev/null || echo 2)"

# -O1 without debug information keeps the build short; the stacks still name functions.
# (-O0 compiles about 40 % faster but its tests ran 316 s against 186 s, and CI as a whole
# took 40 s longer with it: 3055 s against 3015 s.)
# (With GCC 12, its null, nonnull-attribute and returns-nonnull-attribute checks turn off
# -fdelete-null-pointer-checks, and then a constant expression may not compare an object's
# address with nullptr (bridge/bridge_layouts.h LayoutOf): those three are left out (ASan
# still reports a null access, as a SEGV); the lane keeps them out under clang too.)
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
sanitize+=" -fno-sanitize=null,nonnull-attribute,returns-nonnull-attribute"
# clang 14 (Debian's clang, installed for the fuzzer) builds the lane: it compiled the lane in
# about half GCC 12's time (about 620 s against 1,000-1,300 s on two cores) and its unit tests ran
# in 105 s against 143 s. A folder configured with another compiler is configured afresh (CMake
# cannot change a configured folder's compiler): its cache goes, its objects are rebuilt.
compiler=(-DCMAKE_CXX_COMPILER=clang++)
if [ -f "$build/CMakeCache.txt" ] && ! grep -q '^CMAKE_CXX_COMPILER:.*clang++' "$build/CMakeCache.txt"; then
  rm -rf "$build/CMakeCache.txt" "$build/CMakeFiles"
fi
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi

# leaks are checked at exit, except OSMesa's own (its contexts keep a few kB until exit) and
# one known in the task language: a script error (lua_error, a longjmp) in movej skips the
# destructor of the joint vector (src/task/task_api.cc MoveJ)
# the same options hold while the build lists each executable's tests
mkdir -p "$build"
printf 'leak:libOSMesa.so\nleak:vlab::task::*MoveJ\n' >"$build/lsan.supp"
export ASAN_OPTIONS="detect_leaks=1"
export LSAN_OPTIONS="suppressions=$build/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"

echo "vlab: sanitizer lane: configuring $build"
cmake -S . -B "$build" "${compiler[@]}" "${launcher[@]}" -DCMAKE_BUILD_TYPE=Sanitize \
  "-DCMAKE_CXX_FLAGS_SANITIZE=-O1 $sanitize" \
  "-DCMAKE_EXE_LINKER_FLAGS_SANITIZE=$sanitize" "-DCMAKE_SHARED_LINKER_FLAGS_SANITIZE=$sanitize" \
  -DVLAB_WERROR=OFF >/dev/null

log="$build/build.log"
echo "vlab: sanitizer lane: building the libraries and unit tests (log: $log)"
if ! cmake --build "$build" -j "$jobs" --target vlab_unit_tests >"$log" 2>&1; then
  grep -E -B2 -A8 "error|Error" "$log" | head -80 >&2
  echo "vlab: sanitizer lane: build failed, see $log" >&2
  exit 1
fi
echo "vlab: sanitizer lane: configured and built in ${SECONDS} s"

echo "vlab: sanitizer lane: ctest -L unit"
cd "$build"
exec ctest -L unit --output-on-failure -j "$jobs" "$@"

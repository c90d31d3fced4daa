#!/usr/bin/env bash
# Builds the bridge packet fuzzer (libFuzzer, clang 14) and runs it for a
# bounded time; see packet_fuzzer.cc for what it checks.
#
#   tests/fuzz/run_fuzz.sh BUILD_DIR [SECONDS]     default 30 s; 0: build and replay only
#   tests/fuzz/run_fuzz.sh BUILD_DIR --build-only  build only (./test.sh, beside the build)
#
# Steps: build (incremental) into BUILD_DIR; check that the committed corpus
# matches make_corpus; replay tests/fuzz/regressions/* and the committed
# corpus; then fuzz for SECONDS on a copy of the corpus (BUILD_DIR/corpus, kept
# between runs; the committed corpus is never written). Exits non-zero on any
# crash, sanitizer report, leak, timeout or broken invariant, and prints the
# path of the input that caused it. Uses one core to fuzz, two to build
# (VLAB_FUZZ_JOBS).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
build="${1:?usage: run_fuzz.sh BUILD_DIR [SECONDS | --build-only]}"
seconds="${2:-30}"
build_only=0
if [ "$seconds" = --build-only ]; then
  build_only=1
  seconds=0
fi
jobs="${VLAB_FUZZ_JOBS:-2}"
cxx="${VLAB_FUZZ_CXX:-clang++}"

fail() {
  echo "run_fuzz: $*" >&2
  exit 1
}
[[ "$seconds" =~ ^[0-9]+$ ]] || fail "SECONDS must be a whole number, got '$seconds'"

# ---- tools: project dependencies (tools/setup.sh installs them); missing is an error
command -v "$cxx" >/dev/null 2>&1 ||
  fail "$cxx not found: install the Debian package 'clang' (tools/setup.sh lists it)"
runtime_dir="$("$cxx" --print-runtime-dir 2>/dev/null || true)"
for lib in fuzzer asan ubsan_standalone; do
  [ -f "$runtime_dir/libclang_rt.$lib-$(uname -m).a" ] ||
    fail "libFuzzer/sanitizer runtime libclang_rt.$lib missing in '$runtime_dir':" \
      "install the Debian package 'libclang-rt-14-dev' (tools/setup.sh lists it)"
done

# ---- build: objects rebuilt when a source or any bridge header is newer; the fuzzer and the
# corpus generator link the same bridge objects
mkdir -p "$build/obj" "$build/artifacts"
build="$(cd "$build" && pwd)"
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=all"
cxxflags=(-std=c++17 -g -O1 -fno-omit-frame-pointer -pthread -I"$root" -isystem /usr/include/eigen3)
bridge_sources=(bridge/bridge_protocol.cc bridge/bridge_layouts.cc bridge/bridge_endpoint.cc bridge/bridge_session.cc
  bridge/bridge_udp.cc bridge/bridge_describe.cc bridge/bridge_payload.cc)
newest_header=""
for header in "$root"/bridge/*.h; do
  if [ -z "$newest_header" ] || [ "$header" -nt "$newest_header" ]; then newest_header="$header"; fi
done
object() { echo "$build/obj/$(basename "${1%.cc}").o"; }
pids=()
for src in "${bridge_sources[@]}" tests/fuzz/packet_fuzzer.cc tests/fuzz/make_corpus.cc; do
  obj="$(object "$src")"
  if [ -f "$obj" ] && [ "$obj" -nt "$root/$src" ] && [ "$obj" -nt "$newest_header" ]; then continue; fi
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do sleep 0.2; done
  echo "run_fuzz: compiling $src"
  # shellcheck disable=SC2086
  "$cxx" "${cxxflags[@]}" $sanitize -fsanitize=fuzzer-no-link -c "$root/$src" -o "$obj" &
  pids+=($!)
done
for pid in "${pids[@]}"; do wait "$pid" || fail "compilation failed (see above)"; done
bridge_objects=()
for src in "${bridge_sources[@]}"; do bridge_objects+=("$(object "$src")"); done
# link_stale BINARY LINK_FLAG OBJECT...: links BINARY when it is missing or older than an object
link_stale() {
  local binary="$1" flag="$2"
  shift 2
  for obj in "$@"; do
    if [ ! -f "$binary" ] || [ "$obj" -nt "$binary" ]; then
      # shellcheck disable=SC2086
      "$cxx" "${cxxflags[@]}" $sanitize $flag "$@" -o "$binary" || fail "linking $(basename "$binary") failed"
      return 0
    fi
  done
}
fuzzer="$build/packet_fuzzer"
maker="$build/make_corpus"
link_stale "$fuzzer" -fsanitize=fuzzer "${bridge_objects[@]}" "$(object tests/fuzz/packet_fuzzer.cc)"
link_stale "$maker" "" "${bridge_objects[@]}" "$(object tests/fuzz/make_corpus.cc)"
if [ "$build_only" = 1 ]; then
  echo "run_fuzz: built $fuzzer and $maker"
  exit 0
fi

# ---- the committed corpus must still be what the generator writes
"$maker" --check "$here/corpus" ||
  fail "tests/fuzz/corpus is stale: regenerate with '$maker $here/corpus' and commit it"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
common=(-timeout=5 -rss_limit_mb=2048 -max_len=8256 -artifact_prefix="$build/artifacts/")

# ---- replay: known findings and the committed corpus, no mutation
mapfile -t regressions < <(find "$here/regressions" -type f ! -name '*.md' ! -name '.*' 2>/dev/null | sort)
if [ "${#regressions[@]}" -gt 0 ]; then
  echo "run_fuzz: replaying ${#regressions[@]} regression input(s)"
  for input in "${regressions[@]}"; do
    "$fuzzer" "${common[@]}" "$input" >"$build/replay.log" 2>&1 || {
      cat "$build/replay.log"
      fail "regression input still fails: $input (reproduce: $fuzzer $input)"
    }
  done
fi
echo "run_fuzz: replaying the committed corpus"
"$fuzzer" "${common[@]}" -runs=0 "$here/corpus" >"$build/replay.log" 2>&1 || {
  cat "$build/replay.log"
  fail "the committed corpus fails (see above)"
}
[ "$seconds" -gt 0 ] || {
  echo "run_fuzz: replay passed"
  exit 0
}

# ---- fuzz on a copy of the corpus (libFuzzer adds new inputs to the first dir)
work="$build/corpus"
mkdir -p "$work"
cp -n "$here"/corpus/* "$work"/
log="$build/fuzz.log"
echo "run_fuzz: fuzzing for $seconds s (log: $log)"
set +e
"$fuzzer" "${common[@]}" -max_total_time="$seconds" -print_final_stats=1 "$work" 2>&1 | tee "$log" |
  grep -E "^#[0-9]+[[:space:]]+(INITED|DONE)|^Done|Test unit written"
status="${PIPESTATUS[0]}"
set -e

final_stat() { sed -n "s/^stat::$1: *//p" "$log" | tail -1; }
coverage="$(grep -E '^#[0-9]+[[:space:]].*cov:' "$log" | tail -1 | grep -oE 'cov: [0-9]+ ft: [0-9]+ corp: [^ ]+' || true)"
echo "run_fuzz: $(final_stat number_of_executed_units) executions, $(final_stat average_exec_per_sec) exec/s," \
  "peak rss $(final_stat peak_rss_mb) MB; coverage: ${coverage:-unknown} (cov: edges, ft: features, corp: inputs/size)"
if [ "$status" -ne 0 ]; then
  # the report and its stack, from the first line of the finding
  sed -n '/invariant broken\|==ERROR\|runtime error\|ERROR: libFuzzer/,$p' "$log" | grep -v '^INFO\|^stat::' | head -80 >&2
  artifact="$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -1)"
  echo "run_fuzz: FAILED (libFuzzer exit $status); input: ${artifact:-none written}" >&2
  if [ -n "$artifact" ]; then
    echo "run_fuzz: reproduce: $fuzzer $artifact" >&2
    echo "run_fuzz: minimise: $fuzzer -minimize_crash=1 -runs=10000 $artifact" >&2
  fi
  exit "$status"
fi
echo "run_fuzz: no findings"

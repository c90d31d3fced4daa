# Shared set-up for run.sh and test.sh (sourced, not executed).
# Installs the Debian packages vlab needs that are missing (and only those),
# then configures and builds into build/ incrementally. ./test.sh also installs
# the packages only the tests need (VLAB_TEST_APT_PACKAGES); ./run.sh does not.

VLAB_APT_PACKAGES=(
  build-essential cmake pkg-config ninja-build
  libmujoco-dev libqhull-dev libosmesa6-dev
  libeigen3-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev libboost-dev
  python3 clang libclang-rt-14-dev lld
  libgtest-dev
  libopencv-dev libopencv-contrib-dev
  libjs-three
)
# the robot task language embeds Lua 5.4 (src/task/)
VLAB_APT_PACKAGES+=(liblua5.4-dev)
# run logs in HDF5 besides CSV (src/lab/outputs/lab_log_hdf5.*); MATLAB .mat is written by vlab
# itself with zlib (lab_log_mat.*), and read back by the tests with libmatio (built with the rest)
VLAB_APT_PACKAGES+=(libhdf5-dev zlib1g-dev libmatio-dev)
# run logs in MCAP: zstd-compressed chunks and zlib's CRC-32 (src/lab/outputs/lab_mcap.*)
VLAB_APT_PACKAGES+=(libzstd-dev)
# PNG and JPEG through libpng and libjpeg (render/image_codec.*), not OpenCV's imgcodecs, whose
# dependencies every program linking it loads at start-up
VLAB_APT_PACKAGES+=(libpng-dev libjpeg62-turbo-dev)
# vlab identify fits model parameters to logs by nonlinear least squares with Ceres (src/identify/)
VLAB_APT_PACKAGES+=(libceres-dev)

# for the tests only: Octave runs the MATLAB/Octave example (tests/serve/octave_client_test.sh)
VLAB_TEST_APT_PACKAGES=(octave octave-instrument-control)
# for the tests only: the sweep engines (tests/lab/sweep_parallel_test.sh, sweep_slurm_test.sh):
# GNU parallel, and a single-node Slurm with its munge authentication, started by the test
VLAB_TEST_APT_PACKAGES+=(parallel slurm-wlm munge)
# for the tests only: headless Chromium renders vlab view's page (tests/view/browser_test.cc)
VLAB_TEST_APT_PACKAGES+=(chromium)
# for the tests only: format_check (tests/format_check.sh) holds the tree to .clang-format
VLAB_TEST_APT_PACKAGES+=(clang-format)
# for the tests only: Octave loads log.mat, h5py reads log.h5 (tests/lab/log_formats_*)
VLAB_TEST_APT_PACKAGES+=(python3-h5py)

vlab_missing_packages() {
  local pkg missing=()
  for pkg in "${VLAB_APT_PACKAGES[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$pkg")
    fi
  done
  echo "${missing[@]:-}"
}

vlab_install_packages() {
  local missing
  missing="$(vlab_missing_packages)"
  [ -z "$missing" ] && return 0
  echo "vlab: installing missing Debian packages: $missing"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then sudo="sudo"; else
      echo "vlab: need root or sudo to install: $missing" >&2; return 1
    fi
  fi
  local log
  log="$(mktemp)"
  # shellcheck disable=SC2086
  if ! { $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive \
         $sudo apt-get install -y -qq --no-install-recommends $missing; } >"$log" 2>&1; then
    tail -20 "$log" >&2
    echo "vlab: package installation failed" >&2
    rm -f "$log"
    return 1
  fi
  rm -f "$log"
}

# vlab_generator DIR: "-G Ninja" for a build folder not configured yet when ninja is there (one
# scheduler over the whole tree keeps both cores busy, where make's recursion waits at each
# target's boundary), else nothing (a configured folder keeps the generator it was made with)
vlab_generator() {
  if [ ! -f "$1/CMakeCache.txt" ] && command -v ninja >/dev/null 2>&1; then echo "-G Ninja"; fi
}

# vlab_build [CMAKE_OPTION...]: configures build/ on its first build, and again whenever
# options are given (VLAB_WERROR=1 ./test.sh gives -DVLAB_WERROR=ON), then builds everything
vlab_build() {
  local jobs log
  jobs="$(nproc 2>/dev/null || echo 2)"
  if [ ! -f build/CMakeCache.txt ] || [ $# -gt 0 ]; then
    cmake -S . -B build $(vlab_generator build) -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@" >/dev/null
  fi
  log="build/build.log"
  echo "vlab: building (log: $log)"
  if ! cmake --build build -j "$jobs" >"$log" 2>&1; then
    grep -E -B2 -A8 "error|Error" "$log" | head -80 >&2
    echo "vlab: build failed, see $log" >&2
    return 1
  fi
}

# vlab_build_fuzzer: the bridge packet fuzzer and its corpus generator (clang; tests/fuzz/run_fuzz.sh
# --build-only) into build/fuzz on every core, after the build, so that the suite's packet_fuzz
# and packet_fuzz_replay only replay and fuzz (they compile on one core what is stale). A failure
# is the suite's to report: packet_fuzz compiles again and names the error.
vlab_build_fuzzer() {
  local log=build/fuzz-build.log
  echo "vlab: building the packet fuzzer (log: $log)"
  if ! VLAB_FUZZ_JOBS="$(nproc 2>/dev/null || echo 2)" bash tests/fuzz/run_fuzz.sh build/fuzz --build-only >"$log" 2>&1; then
    echo "vlab: building the packet fuzzer failed, see $log (packet_fuzz will fail)" >&2
  fi
}

# vlab_install_node_packages: the tests' Node packages (tests/node/package.json: the MCAP
# reference reader, the Foxglove WebSocket client, ROS 2 message decoders, Khronos' glTF
# validator) into tests/node/node_modules, from the npm registry, exactly as package-lock.json
# pins them (npm ci); again only when the lock file changed. Node.js and npm come from Debian
# when the machine has none.
vlab_install_node_packages() {
  local dir=tests/node
  if [ -f "$dir/node_modules/.package-lock.json" ] && [ ! "$dir/package-lock.json" -nt "$dir/node_modules/.package-lock.json" ]; then
    return 0
  fi
  echo "vlab: installing the tests' Node packages into $dir/node_modules"
  if ! npm ci --prefix "$dir" --no-audit --no-fund --loglevel=error >/dev/null; then
    echo "vlab: npm ci failed in $dir (the tests that read MCAP, speak Foxglove's protocol or validate glTF need it)" >&2
    return 1
  fi
}

# vlab_setup [--tests]: --tests (./test.sh) also installs the packages only the tests need.
# Both build build/ with the same flags, so ./run.sh then ./test.sh builds once. With
# VLAB_WERROR=1 in the environment (.ci/run sets it) build/ is configured with -Werror
# (VLAB_WERROR: any compiler warning fails the build); the option then stays in build/'s
# cache, as every CMake option does, until it is configured again.
vlab_setup() {
  local options=()
  if [ "${1:-}" = --tests ]; then
    VLAB_APT_PACKAGES+=("${VLAB_TEST_APT_PACKAGES[@]}")
    command -v npm >/dev/null 2>&1 || VLAB_APT_PACKAGES+=(nodejs npm)
  fi
  if [ "${VLAB_WERROR:-0}" = 1 ]; then options=(-DVLAB_WERROR=ON); fi
  vlab_install_packages
  if [ "${1:-}" = --tests ]; then vlab_install_node_packages; fi
  vlab_build "${options[@]}"
  if [ "${1:-}" = --tests ]; then vlab_build_fuzzer; fi
}

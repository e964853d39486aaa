#!/usr/bin/env bash
# One set-up path: installs the Debian packages the engine needs (only when
# some are missing), configures a Release build in build/ and builds.
#
#   ./build.sh          install + build
#   ./build.sh demo     install + build + run the animated demo
#   ./build.sh test     install + build + run every test: the suite on the
#                       Release build, then on a Clang build (with the GCC /
#                       Clang byte comparison), on an ASan + UBSan build, and
#                       every fuzz target (TEST_STAGES picks, see below)
#   ./build.sh bench    install + build + run the benchmarks (minutes)
#
# Environment: BUILD_DIR (default build), SANITIZE=1 for an ASan+UBSan build,
# JOBS (default: number of cores), TEST_STAGES (default "release clang
# sanitize fuzz"; "release" alone for a quick run), FUZZ_SECONDS (default 30,
# per fuzz target), FUZZ_SEED (default 1: every run fuzzes the same inputs, see
# fuzz/run.sh; "random" explores for FUZZ_SECONDS each instead).
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(
  build-essential cmake pkg-config ccache git
  libglm-dev libglfw3-dev libosmesa6-dev libgl-dev
  libopenvdb-dev libboost-dev libboost-iostreams-dev libtbb-dev libimath-dev libopenexr-dev libblosc-dev
  libgdal-dev
  doctest-dev libpng-dev libtomlplusplus-dev libcli11-dev libimgui-dev
  python3-dev pybind11-dev python3-numpy
  xvfb xauth xdotool
  clang libclang-rt-14-dev
)

# the benchmarks draw their plots with matplotlib (bench/plots/)
if [ "${1:-}" = bench ]; then PACKAGES+=(python3-matplotlib); fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "build.sh: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}
cmake_args=(-S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release)
if [ "${SANITIZE:-0}" = 1 ]; then cmake_args+=(-DTERRAIN_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo); fi
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ] || [ CMakeLists.txt -nt "$BUILD_DIR/CMakeCache.txt" ] || [ "${SANITIZE:-0}" = 1 ]; then
  cmake "${cmake_args[@]}" >/dev/null
fi
cmake --build "$BUILD_DIR" -j "$JOBS"

case "${1:-}" in
  "") ;;
  demo) shift; exec "$BUILD_DIR/terrain" demo "$@" ;;
  test)
    shift
    # the sanitizer build: third-party leaks at exit (Mesa) are not ours
    export LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
    for stage in ${TEST_STAGES:-release clang sanitize fuzz}; do
      echo "build.sh test: stage $stage"
      case "$stage" in
        release) (cd "$BUILD_DIR" && ctest --output-on-failure "$@") ;;
        clang)  # a second compiler: warning-free, and the same bytes as the GCC build (ctest compiler_determinism)
          CC=clang CXX=clang++ cmake -S . -B build-clang -DCMAKE_BUILD_TYPE=Release -DTERRAIN_BUILD_BENCH=OFF \
            -DTERRAIN_COMPARE_BUILD="$PWD/$BUILD_DIR" >/dev/null
          cmake --build build-clang -j "$JOBS"
          (cd build-clang && ctest --output-on-failure "$@") ;;
        sanitize)  # every test but the long run, which is the benchmarks' (its 2 000 ticks take minutes
                   # under ASan; the unit tests cover each stage), so the benchmarks are not built
          cmake -S . -B build-asan -DTERRAIN_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTERRAIN_BUILD_BENCH=OFF >/dev/null
          cmake --build build-asan -j "$JOBS"
          (cd build-asan && ctest --output-on-failure "$@") ;;
        fuzz)  # each libFuzzer target: its saved regressions, then a reproducible FUZZ_SECONDS from its seeds
          CC=clang CXX=clang++ cmake -S . -B build-fuzz -DTERRAIN_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
            -DTERRAIN_BUILD_TESTS=OFF -DTERRAIN_BUILD_BENCH=OFF >/dev/null
          cmake --build build-fuzz -j "$JOBS" --target fuzz
          seed=${FUZZ_SEED:-1}
          [ "$seed" = random ] && seed=
          FUZZ_SEED=$seed bash fuzz/run.sh build-fuzz "${FUZZ_SECONDS:-30}" ;;
        *) echo "build.sh: unknown test stage '$stage' (use: release clang sanitize fuzz)" >&2; exit 2 ;;
      esac
    done ;;
  bench) shift; exec bash bench/run.sh "$BUILD_DIR" "$@" ;;
  *) echo "build.sh: unknown command '$1' (use: demo, test, bench)" >&2; exit 2 ;;
esac

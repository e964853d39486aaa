#!/usr/bin/env bash
# One set-up path: installs the Debian packages the engine needs (only when
# some are missing), configures a Release build in build/ and builds.
#
#   ./build.sh          install + build
#   ./build.sh demo     install + build + run the animated demo
#   ./build.sh test     install + build + run every test
#   ./build.sh bench    install + build + run the benchmarks (minutes)
#
# Environment: BUILD_DIR (default build), SANITIZE=1 for an ASan+UBSan build,
# JOBS (default: number of cores).
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(
  build-essential cmake pkg-config ccache git
  libglm-dev libglfw3-dev libosmesa6-dev libgl-dev
  libopenvdb-dev libboost-dev libboost-iostreams-dev libtbb-dev libimath-dev libopenexr-dev libblosc-dev
  doctest-dev libpng-dev libtomlplusplus-dev libcli11-dev libimgui-dev
  xvfb xauth xdotool
)

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
    if [ "${SANITIZE:-0}" = 1 ]; then export LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"; fi
    cd "$BUILD_DIR" && exec ctest --output-on-failure "$@" ;;
  bench) shift; exec bash bench/run.sh "$BUILD_DIR" "$@" ;;
  *) echo "build.sh: unknown command '$1' (use: demo, test, bench)" >&2; exit 2 ;;
esac

#!/usr/bin/env bash
# The test `downstream`: installs a build of this project to a prefix inside
# its build folder, then configures, builds and runs the project beside this
# script against that prefix, as a user of the installed package would.
# Usage: run.sh CMAKE BUILD_DIR DOWNSTREAM_SOURCE CXX_COMPILER [COMPILER_LAUNCHER]
# Prints one line naming the failed step (after that step's last output lines)
# and exits non-zero on failure.
set -u
CMAKE=$1
BUILD=$2
SRC=$3
CXX=$4
LAUNCHER=${5:-}

work="$BUILD/downstream_test"
prefix="$work/prefix"
log="$work/log.txt"
rm -rf "$work"
mkdir -p "$work"

# Runs one step with its output in $log; on failure shows the log's tail.
step() {
  local what=$1
  shift
  if ! "$@" >"$log" 2>&1; then
    tail -n 30 "$log"
    echo "downstream: FAILED: $what (full output: $log)"
    exit 1
  fi
}

step "cmake --install $BUILD --prefix $prefix" "$CMAKE" --install "$BUILD" --prefix "$prefix"
configure=(-S "$SRC" -B "$work/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix"
           -DCMAKE_CXX_COMPILER="$CXX")
if [ -n "$LAUNCHER" ]; then configure+=(-DCMAKE_CXX_COMPILER_LAUNCHER="$LAUNCHER"); fi
step "configuring $SRC against $prefix (find_package(terrain))" "$CMAKE" "${configure[@]}"
step "building $SRC" "$CMAKE" --build "$work/build"
step "running the downstream program" "$work/build/terrain_downstream"
cat "$log"
echo "downstream: ok"

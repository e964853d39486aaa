#!/usr/bin/env bash
# Refreshes bench/results/: runs every suite whose results are committed there
# (with its default options; gi-bound-diagnosis with the --frames its committed
# file has) and so redraws the plots. Slow: about 2.5 hours on the shared 2-core
# machine (bench/README.md lists each suite's time), most of it computing
# ground truths and the long run.
# Usage: bench/run.sh [build-dir] [suite ...]   (default: every suite below)
set -euo pipefail
cd "$(dirname "$0")/.."
B=build
if [ $# -gt 0 ] && [ -f "$1/CMakeCache.txt" ]; then B=$1; shift; fi  # a build folder, not a suite

# suite -> its terrain_bench arguments (gi runs its five modes in one process,
# so they share the ground truths it computes)
declare -A ARGS=(
  [sim]="sim"
  [render]="render"
  [scaling]="scaling"
  [table1]="table1"
  [speed-vs-error]="speed-vs-error"
  [gi]="gi accuracy convergence timing dems frame-time"
  [gi-sunsky]="gi-sunsky"
  [gi-indirect]="gi-indirect"
  [gi-glossy]="gi-glossy"
  [gi-incremental]="gi-incremental"
  [gi-bound-diagnosis]="gi-bound-diagnosis --frames 12"
  [long-run]="long-run"
  [svf-saga]="svf-saga --terrain $B/terrain"
)
ORDER=(sim render scaling table1 speed-vs-error gi gi-sunsky gi-indirect gi-glossy gi-incremental gi-bound-diagnosis long-run svf-saga)
[ $# -gt 0 ] && ORDER=("$@")

for suite in "${ORDER[@]}"; do
  [ -n "${ARGS[$suite]+set}" ] || { echo "bench/run.sh: unknown suite '$suite' (one of: ${!ARGS[*]})" >&2; exit 2; }
done
cmake --build "$B" -j2 --target terrain terrain_bench

for suite in "${ORDER[@]}"; do
  echo "== terrain_bench ${ARGS[$suite]}"
  start=$(date +%s)
  # shellcheck disable=SC2086 # the arguments are meant to split
  "$B/terrain_bench" ${ARGS[$suite]}
  echo "== $suite: $(($(date +%s) - start)) s"
done

#!/usr/bin/env bash
# Runs every benchmark suite and writes bench/results/. Takes about half an hour.
# Usage: bench/run.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:-build}
# The suites the separate bench_* programs used to run, in the same order, with their default work.
for suite in gi gi-glossy gi-indirect render sim; do
  echo "== terrain_bench $suite"
  "$B/terrain_bench" "$suite"
done

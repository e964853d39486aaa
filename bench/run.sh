#!/usr/bin/env bash
# Runs every benchmark and writes bench/results/. Takes minutes.
# Usage: bench/run.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:-build}
for b in "$B"/bench_*; do
  [ -x "$b" ] || continue
  echo "== $b"
  "$b"
done

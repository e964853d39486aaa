#!/usr/bin/env bash
# The sky-view factor side by side with SAGA's (saga_cmd ta_lighting 3) on Mont Blanc:
# time and error against exact references, written to bench/results/svf_saga.md and .csv.
# SAGA is used only when saga_cmd is on the PATH (Debian: apt-get install saga); it is not
# a build or test dependency, and without it the results hold the engine's rows alone.
# Usage: bench/svf_saga.sh [build-dir] [terrain_bench svf-saga options: --runs N, --cache DIR, ...]
# The exact references take minutes on 2 cores; --cache DIR keeps them across runs.
set -euo pipefail
cd "$(dirname "$0")/.."
B=build
if [ $# -gt 0 ] && [ "${1#-}" = "$1" ]; then B=$1; shift; fi
cmake --build "$B" -j2 --target terrain terrain_bench
exec "$B/terrain_bench" svf-saga --terrain "$B/terrain" "$@"

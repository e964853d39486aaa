#!/usr/bin/env bash
# Runs the fuzz targets of a TERRAIN_FUZZ build: first every input saved in
# fuzz/regressions/<target>/ (each once: a fixed finding must stay fixed),
# then each target for SECONDS from its seeds in fuzz/corpus/<target>/.
# Fails when any input crashes, trips ASan or UBSan, leaks, runs out of time
# or memory, or breaks a target's checks (fuzz/fuzz_input.h).
#
#   CC=clang CXX=clang++ cmake -S . -B build-fuzz -DTERRAIN_FUZZ=ON \
#     -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTERRAIN_BUILD_TESTS=OFF -DTERRAIN_BUILD_BENCH=OFF
#   cmake --build build-fuzz -j2 --target fuzz
#   fuzz/run.sh build-fuzz 30        # 30 s per target; 0: the regressions only
#
# Inputs the fuzzer finds (crash-*, leak-*, timeout-*, oom-*) are kept in
# BUILD_DIR/fuzz-findings/. To keep one as a regression, minimise it
# (BUILD_DIR/fuzz/<target> -minimize_crash=1 -runs=20000 FILE), name it for
# what it does and add it under fuzz/regressions/<target>/ with the fix.
# New coverage-increasing inputs stay in BUILD_DIR/fuzz-corpus/, not in git.
# Usage: fuzz/run.sh BUILD_DIR [SECONDS]
set -uo pipefail
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$(realpath "$1")
SECONDS_EACH=${2:-30}

# Largest input per target: room for the seeds and some growth, small enough
# that a multi-gigabyte allocation can only come from a size the file declares.
declare -A max_len=(
  [albedo_png]=16384 [equirect_exr]=16384 [equirect_hdr]=16384 [exponent_png]=16384
  [number_list]=4096 [png_heightmap]=16384 [scene_toml]=8192 [vdb]=131072
)
# An allocation over 1 GiB (the largest legitimate one from such small files is
# a few MB) or a process over 2 GiB is a finding, as is an input taking 10 s.
limits=(-rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=10)
# OpenVDB 10 and OpenEXR 3.1 allocate what a file's header declares (metadata,
# names, attributes) inside their open calls, before our readers see a size;
# these targets fuzz in fork mode past such out-of-memory inputs, counting and
# keeping them, and still fail on anything else. Their regressions run strictly.
library_ooms=" equirect_exr vdb "
# An impossible allocation throws std::bad_alloc, as it does without ASan.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1}

findings=$BUILD/fuzz-findings
mkdir -p "$findings"
fail=0
for target in $(printf '%s\n' "${!max_len[@]}" | sort); do
  bin=$BUILD/fuzz/$target
  if [ ! -x "$bin" ]; then
    echo "fuzz: $bin is missing (build the target fuzz of a TERRAIN_FUZZ build)"
    fail=1
    continue
  fi
  regressions=("$SRC/fuzz/regressions/$target"/*)
  if [ -e "${regressions[0]}" ]; then
    log=$findings/$target-regressions.log
    if "$bin" "${limits[@]}" "${regressions[@]}" >"$log" 2>&1; then
      echo "fuzz: $target: ${#regressions[@]} regression inputs pass"
    else
      echo "fuzz: $target: a regression input fails (log: $log):"
      grep -aE "Running: |ERROR|SUMMARY|runtime error|terrain fuzz" "$log" | head -n 12
      fail=1
    fi
  fi
  [ "$SECONDS_EACH" = 0 ] && continue
  log=$findings/$target.log
  corpus=$BUILD/fuzz-corpus/$target
  mkdir -p "$corpus"
  mode=()
  [[ $library_ooms == *" $target "* ]] && mode=(-fork=1 -ignore_ooms=1)
  if "$bin" "${limits[@]}" "${mode[@]}" -max_len="${max_len[$target]}" -max_total_time="$SECONDS_EACH" \
    -artifact_prefix="$findings/$target-" -print_final_stats=1 "$corpus" "$SRC/fuzz/corpus/$target" >"$log" 2>&1; then
    runs=$(grep -aoE 'stat::number_of_executed_units: *[0-9]*|^#[0-9]+' "$log" | tail -n 1 | grep -oE '[0-9]+$')
    ooms=$(grep -aoE 'oom/timeout/crash: [0-9]+' "$log" | tail -n 1 | grep -oE '[0-9]+$')
    echo "fuzz: $target: $SECONDS_EACH s, $runs inputs, no finding${ooms:+ ($ooms out-of-memory inputs kept, not counted)}"
  else
    echo "fuzz: $target: FINDING (log: $log):"
    grep -aE "ERROR|SUMMARY|runtime error|terrain fuzz|Test unit written" "$log" | head -n 12
    fail=1
  fi
done
exit $fail

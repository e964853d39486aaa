#!/usr/bin/env bash
# Runs the fuzz targets of a TERRAIN_FUZZ build: first every input saved in
# fuzz/regressions/<target>/ (each once: a fixed finding must stay fixed),
# then each target for SECONDS from its seeds in fuzz/corpus/<target>/.
# Fails when any input crashes, trips ASan or UBSan, leaks, runs out of time or memory, or breaks a target's checks (fuzz/fuzz_input.h).
#
#   CC=clang CXX=clang++ cmake -S . -B build-fuzz -DTERRAIN_FUZZ=ON \
#     -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTERRAIN_BUILD_TESTS=OFF -DTERRAIN_BUILD_BENCH=OFF
#   cmake --build build-fuzz -j2 --target fuzz
#   fuzz/run.sh build-fuzz 30        # 30 s per target; 0: the regressions only
#   FUZZ_SEED=1 fuzz/run.sh build-fuzz 30   # the same inputs on every run
#
# With FUZZ_SEED set (the test command sets it) a run is reproducible: each
# target starts from its committed seeds alone, draws its mutations from that
# seed and runs a fixed number of inputs, SECONDS times its rate on a 2-core
# machine (inputs_per_second below), so that CI and a developer running the
# same commit fuzz the same inputs and get the same answer (with the
# compiler and libraries of Debian 12). Without it the
# seed is random and each target runs for SECONDS, to explore.
#
# Inputs the fuzzer finds (crash-*, leak-*, timeout-*, oom-*) are kept in
# BUILD_DIR/fuzz-findings/<target>/ until the next run. To keep one as a
# regression, minimise it (BUILD_DIR/fuzz/<target> -minimize_crash=1
# -runs=20000 FILE), name it for what it does and add it under
# fuzz/regressions/<target>/ with the fix.
# New coverage-increasing inputs stay in BUILD_DIR/fuzz-corpus/, not in git.
# Usage: fuzz/run.sh BUILD_DIR [SECONDS [TARGET...]]   (default: every target)
set -uo pipefail
SRC=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$(realpath "$1")
SECONDS_EACH=${2:-30}
shift $(($# < 2 ? $# : 2))

# Largest input per target: room for the seeds and some growth, small enough
# that a multi-gigabyte allocation can only come from a size the file declares.
declare -A max_len=(
  [albedo_png]=16384 [equirect_exr]=16384 [equirect_hdr]=16384 [exponent_png]=16384 [exr_heightmap]=16384
  [geotiff]=16384 [number_list]=4096 [png_heightmap]=16384 [scene_toml]=8192 [vdb]=131072
)
# Inputs per second of each target on a 2-core machine (Clang 14, ASan + UBSan).
declare -A inputs_per_second=(
  [albedo_png]=39000 [equirect_exr]=25000 [equirect_hdr]=35000 [exponent_png]=41000 [exr_heightmap]=11000
  [geotiff]=400 [number_list]=33000 [png_heightmap]=43000 [scene_toml]=20000 [vdb]=7000
)
# An allocation over 1 GiB (the largest legitimate one from such small files is
# a few MB) or a process over 2 GiB is a finding, as is an input taking 10 s.
limits=(-rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=10)
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1}

# Fuzzes $target for SECONDS_EACH (or its fixed number of inputs from
# FUZZ_SEED); fails on a finding.
fuzz_target() {
  local budget=(-max_total_time="$SECONDS_EACH") fixed_addresses=()
  if [ -n "${FUZZ_SEED:-}" ]; then
    # -reload=0: libFuzzer re-reads its corpus folder every second otherwise,
    # which makes what it mutates depend on time. Pointers compared in the
    # code reach its table of compared values, so addresses are fixed too
    # (no ASLR) where the machine allows it.
    budget=(-seed="$FUZZ_SEED" -runs=$((SECONDS_EACH * ${inputs_per_second[$target]})) -reload=0)
    setarch "$(uname -m)" -R true 2>/dev/null && fixed_addresses=(setarch "$(uname -m)" -R)
    rm -rf "$corpus" && mkdir -p "$corpus"  # the seeds alone, as on a fresh clone
  fi
  "${fixed_addresses[@]}" "$bin" "${limits[@]}" -max_len="${max_len[$target]}" "${budget[@]}" \
    -artifact_prefix="$findings/$target/" -print_final_stats=1 "$corpus" "$SRC/fuzz/corpus/$target" >"$log" 2>&1
}

findings=$BUILD/fuzz-findings
mkdir -p "$findings"
fail=0
targets=("$@")
((${#targets[@]})) || targets=($(printf '%s\n' "${!max_len[@]}" | sort))
for target in "${targets[@]}"; do
  if [ -z "${max_len[$target]:-}" ]; then
    echo "fuzz: no target $target (targets: ${!max_len[*]})"
    fail=1
    continue
  fi
  bin=$BUILD/fuzz/$target
  if [ ! -x "$bin" ]; then
    echo "fuzz: $bin is missing (build the target fuzz of a TERRAIN_FUZZ build)"
    fail=1
    continue
  fi
  # each regression input on its own, so that every failing one is named
  passed=0
  for input in "$SRC/fuzz/regressions/$target"/*; do
    [ -e "$input" ] || continue
    log=$findings/$target-regression-$(basename "$input").log
    if "$bin" "${limits[@]}" "$input" >"$log" 2>&1; then
      rm "$log"
      passed=$((passed + 1))
    else
      echo "fuzz: $target: regression $(basename "$input") fails (log: $log):"
      grep -aE "ERROR|SUMMARY|runtime error|terrain fuzz" "$log" | head -n 4 | cut -c 1-300
      fail=1
    fi
  done
  [ $passed = 0 ] || echo "fuzz: $target: $passed regression inputs pass"
  [ "$SECONDS_EACH" = 0 ] && continue
  log=$findings/$target.log
  corpus=$BUILD/fuzz-corpus/$target
  mkdir -p "$corpus"
  rm -rf "$findings/$target"  # the saved inputs of an earlier run
  mkdir -p "$findings/$target"
  if fuzz_target; then
    runs=$(grep -aoE 'stat::number_of_executed_units: *[0-9]*|^#[0-9]+' "$log" | tail -n 1 | grep -oE '[0-9]+$')
    if [ -n "${FUZZ_SEED:-}" ]; then
      echo "fuzz: $target: seed $FUZZ_SEED, $runs inputs, no finding"
    else
      echo "fuzz: $target: $SECONDS_EACH s, $runs inputs, no finding"
    fi
  else
    echo "fuzz: $target: FINDING (log: $log):"
    grep -aE "ERROR|SUMMARY|runtime error|terrain fuzz|Test unit written" "$log" | head -n 12
    fail=1
  fi
done
exit $fail

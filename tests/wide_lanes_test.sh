#!/usr/bin/env bash
# The 8-wide lane types (core/simd.h F8, I8) must never cross a function
# boundary in the compiled code: their kernels are compiled without AVX and
# become AVX code only by being inlined into a [[gnu::target("avx2")]] wrapper,
# and a 32-byte vector passed between functions of which one lacks AVX has a
# different ABI (the reason simd.h may silence -Wpsabi). GCC's flatten inlines
# a wrapper's whole call tree, Clang's only the wrapper's direct calls, so a
# kernel helper that the optimiser leaves out of line would turn into slow
# SSE2 emulation of the 8-wide code (and, called from AVX code, a wrong ABI).
# Any function left out of line with such a type in its signature or template
# arguments appears as a symbol mangling "Dv8_" (a vector of 8): there must be
# none. Usage: wide_lanes_test.sh LIBRARY...
set -uo pipefail
fail=0
for lib in "$@"; do
  if ! syms=$(nm --defined-only "$lib"); then
    echo "wide_lanes: cannot read $lib"
    fail=1
    continue
  fi
  wide=$(awk '$NF ~ /Dv8_/ {print $NF}' <<<"$syms" | sort -u)
  if [ -n "$wide" ]; then
    echo "wide_lanes: $(basename "$lib") has out-of-line functions with 8-wide lanes:"
    c++filt <<<"$wide" | sed 's/^/  /'
    fail=1
  fi
done
exit $fail

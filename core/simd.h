#pragma once
// SIMD lanes over GCC vector extensions: the one dialect every grid and GI
// kernel is written in.
//
// Lane types: float (one cell), F4 (4 lanes, SSE2: the x86-64 baseline) and
// F8 (8 lanes, AVX2). A kernel is written once, templated on the lane type:
// the simulation's interior cells run four at a time and edge cells one at a
// time with the same arithmetic; the GI's hot kernels are compiled for F4 and
// again for F8 (see "width-generic kernels" below). Every lane op is a
// correctly rounded IEEE-754 add/sub/mul/div/sqrt or a select, so a cell's
// result does not depend on which path (or thread) computed it. Explicit
// vectors rather than auto-vectorisation because the build keeps
// -fmath-errno and -ftrapping-math (no fast-math, for reproducible results),
// under which GCC will not vectorise sqrt, guarded divisions or upwind
// selects by itself.
#include <bit>
#include <cmath>
#include <cstring>
#include <type_traits>

namespace terrain::simd {

using F4 = float __attribute__((vector_size(16)));

// ---- width-generic kernels: F4 (SSE2) and F8 (AVX2) -------------------------
// A hot kernel written once over V = F4 or F8 is compiled twice: as usual, and
// inside a [[gnu::target("avx2"), gnu::flatten]] wrapper that inlines the F8
// instance (wideEnabled() picks one at run time). The helpers below are
// always-inline (the two AVX ones plain inline: they may only be inlined into
// AVX code, which flatten does). Both paths use the same correctly rounded
// lane-wise IEEE operations and neither fuses a multiply-add (the wrappers
// enable AVX2 but not FMA), so they give bit-identical results.
// F8 values only pass between inlined helpers; GCC's note that their
// out-of-line ABI would differ without AVX does not apply (silenced for every
// file that includes this header: instances are made where kernels use them).
#pragma GCC diagnostic ignored "-Wpsabi"
using I4 = int __attribute__((vector_size(16)));
using F8 = float __attribute__((vector_size(32)));
using I8 = int __attribute__((vector_size(32)));
template <class V>
struct LaneTraits;
template <>
struct LaneTraits<float> {
    using I = int;
    static constexpr int n = 1;
};
template <>
struct LaneTraits<F4> {
    using I = I4;
    static constexpr int n = 4;
};
template <>
struct LaneTraits<F8> {
    using I = I8;
    static constexpr int n = 8;
};
/// Lanes of a lane type: 1, 4 or 8.
template <class V>
inline constexpr int kLaneCount = LaneTraits<V>::n;

// The 8-wide sqrt and sign mask work on the two 4-wide halves with SSE2
// builtins: an AVX builtin would need the helper to be an AVX function, and
// Clang rejects a call that passes F8 from a function without AVX (the F8
// kernel instance, which only its AVX2 wrapper makes AVX code by inlining it)
// to one with AVX. Inlined into the wrapper they become VEX instructions.
[[gnu::always_inline]] inline F4 lowHalf(F8 x) { return __builtin_shufflevector(x, x, 0, 1, 2, 3); }
[[gnu::always_inline]] inline F4 highHalf(F8 x) { return __builtin_shufflevector(x, x, 4, 5, 6, 7); }
[[gnu::always_inline]] inline F8 joinHalves(F4 lo, F4 hi) {
    return __builtin_shufflevector(lo, hi, 0, 1, 2, 3, 4, 5, 6, 7);
}

[[gnu::always_inline]] inline float sqrtv(float x) { return std::sqrt(x); }
[[gnu::always_inline]] inline F4 sqrtv(F4 x) { return __builtin_ia32_sqrtps(x); }
[[gnu::always_inline]] inline F8 sqrtv(F8 x) { return joinHalves(sqrtv(lowHalf(x)), sqrtv(highHalf(x))); }
/// One bit per lane: the lane's sign bit (a comparison mask's "true").
[[gnu::always_inline]] inline int laneBits(I4 m) { return __builtin_ia32_movmskps(reinterpret_cast<F4>(m)); }
[[gnu::always_inline]] inline int laneBits(I8 m) {
    const F8 f = reinterpret_cast<F8>(m);
    return laneBits(reinterpret_cast<I4>(lowHalf(f))) | laneBits(reinterpret_cast<I4>(highHalf(f))) << 4;
}

template <class T>
[[gnu::always_inline]] inline T load(const float* p) {
    if constexpr (std::is_same_v<T, float>) {
        return *p;
    } else {
        T v;
        std::memcpy(&v, p, sizeof v);
        return v;
    }
}
template <class T>
[[gnu::always_inline]] inline void store(float* p, T v) {
    if constexpr (std::is_same_v<T, float>)
        *p = v;
    else
        std::memcpy(p, &v, sizeof v);
}
template <class T>
[[gnu::always_inline]] inline T splat(float x) {
    if constexpr (std::is_same_v<T, float>)
        return x;
    else
        return T{} + x;
}
template <class T>
[[gnu::always_inline]] inline T vmax(T a, T b) {
    return a > b ? a : b;
}
template <class T>
[[gnu::always_inline]] inline T vmin(T a, T b) {
    return a < b ? a : b;
}

// Deterministic float atan (Cephes atanf: range reduction to |x| <= tan(pi/8),
// then a degree-9 odd minimax polynomial; ~1e-7 relative): a pure function of
// its argument, so bit-identical for any thread count. Written for a short
// dependency chain, which is what bounds the kernels that call it (their
// iterations wait on it): the sign is a bit mask, and the polynomial is
// evaluated as x + x^3 ((c4 z - c3) z^2 + (c2 z - c1)), z = x^2 (Estrin's
// scheme), three multiply-add levels instead of Horner's five.
template <class V>
[[gnu::always_inline]] inline V atanv(V t) {
    using I = typename LaneTraits<V>::I;
    const V zero = splat<V>(0.0f), one = splat<V>(1.0f);
    const I sign = std::bit_cast<I>(t) & static_cast<int>(0x80000000u);
    const V x = std::bit_cast<V>(std::bit_cast<I>(t) ^ sign);  // |t|
    const auto big = x > splat<V>(2.414213562373095f);
    const auto mid = (x > splat<V>(0.4142135623730950f)) & ~big;
    // one division: -1 / x, (x - 1) / (x + 1) or x / 1
    const V xr = (big ? -one : (mid ? x - one : x)) / (big ? x : (mid ? x + one : one));
    const V y0 = big ? splat<V>(1.5707963267948966f) : (mid ? splat<V>(0.7853981633974483f) : zero);
    const V z = xr * xr;
    const V z2 = z * z, xr3 = xr * z;
    const V q = (splat<V>(8.05374449538e-2f) * z - splat<V>(1.38776856032e-1f)) * z2 +
                (splat<V>(1.99777106478e-1f) * z - splat<V>(3.33329491539e-1f));
    const V r = y0 + (xr + xr3 * q);
    return std::bit_cast<V>(std::bit_cast<I>(r) ^ sign);
}

/// Kernels with an 8-wide AVX2 variant (gi/indirect.cpp) use it when the
/// processor has AVX2 and it is enabled (the default). The variants give
/// bit-identical results (no fused multiply-add in either); tests and
/// benchmarks switch it off to compare. Not thread-safe: set it between frames.
inline bool& wideFlag() {
    static bool on = __builtin_cpu_supports("avx2");
    return on;
}
inline bool wideEnabled() { return wideFlag(); }
/// Returns whether the wide variants are now in use (false without AVX2).
inline bool setWideEnabled(bool on) {
    wideFlag() = on && __builtin_cpu_supports("avx2");
    return wideFlag();
}

}  // namespace terrain::simd

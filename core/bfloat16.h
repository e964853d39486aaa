#pragma once
// bfloat16 storage: the upper 16 bits of an IEEE-754 float (sign, the full
// 8-bit exponent, 7 stored mantissa bits: a relative precision of 2^-9).
// For large fields that a kernel streams from memory and that tolerate that
// precision: half the bytes of float, the same range, and a conversion that
// is exact one way (bfloat16 -> float is a shift) and plain integer
// arithmetic the other, so every lane width and every compiler give the same
// bits.
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "core/simd.h"

namespace terrain {

/// x rounded to the nearest bfloat16 (ties to even). x must be finite; one
/// within 2^-9 of the largest float rounds to infinity.
inline std::uint16_t toBfloat16(float x) {
    std::uint32_t u;
    std::memcpy(&u, &x, sizeof u);
    u += 0x7FFFu + ((u >> 16) & 1u);
    return static_cast<std::uint16_t>(u >> 16);
}

/// The float a bfloat16 stands for (exact).
inline float fromBfloat16(std::uint16_t h) {
    const std::uint32_t u = static_cast<std::uint32_t>(h) << 16;
    float x;
    std::memcpy(&x, &u, sizeof x);
    return x;
}

/// out[i] = toBfloat16(in[i]), i < n.
inline void packBfloat16(const float* in, std::size_t n, std::uint16_t* out) {
    for (std::size_t i = 0; i < n; ++i) out[i] = toBfloat16(in[i]);
}

namespace simd {

using U16x4 = unsigned short __attribute__((vector_size(8)));
using U16x8 = unsigned short __attribute__((vector_size(16)));
using U32x4 = unsigned int __attribute__((vector_size(16)));
using U32x8 = unsigned int __attribute__((vector_size(32)));

/// Lanes of V (F4 or F8) from as many consecutive bfloat16 values (exact):
/// each widened to 32 bits and shifted into the upper half.
template <class V>
[[gnu::always_inline]] inline V loadBfloat16(const std::uint16_t* p) {
    using Half = std::conditional_t<kLaneCount<V> == 8, U16x8, U16x4>;
    using Word = std::conditional_t<kLaneCount<V> == 8, U32x8, U32x4>;
    Half h;
    std::memcpy(&h, p, sizeof h);
    const Word w = __builtin_convertvector(h, Word) << 16;
    return reinterpret_cast<V>(w);
}

}  // namespace simd

}  // namespace terrain

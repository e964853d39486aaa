#pragma once
// Order-4 normalised Legendre polynomial (NLP) basis on z = cos(theta) in
// [-1, 1] (Nowrouzezahrai & Snyder 2009, Section 4) and the closed-form
// occlusion vector (Eq. 10).
//
// NLP_l(z) = sqrt((2l+1)/2) P_l(z), from Rodrigues' formula. (The vector
// printed in Section 4 has wrong constants for l = 2, 3; the closed form of
// v^-(sigma) printed below it is right; tests/test_gi_sh.cpp checks the
// basis for orthonormality.)
//
// Elevation functions are parameterised by the blocking angle omega from the
// horizon up, z = sin(omega). Kernels never call atan: they carry the slope
// t = tan(omega) and use sin(omega) = t / sqrt(1 + t^2).

#include <cmath>

namespace terrain::gi {

inline constexpr int kNlpCount = 4;

/// NLP_l(z), l = 0..3.
void nlpEvaluate(double z, double out[kNlpCount]);

/// Eq. 10: v^-(sigma) = integral over z in [-1, sin sigma] of NLP(z) dz,
/// the NLP projection of "occluded below elevation sigma". Argument sin(sigma).
/// [ (s+1)/sqrt2, -3c^2/(2 sqrt6), -5 s c^2/(2 sqrt10), 7 c^2 (5c^2 - 4)/(8 sqrt14) ]
/// with s = sin sigma, c^2 = 1 - s^2.
template <class T>
inline void nlpOcclusion(T s, T out[kNlpCount]) {
    const T c2 = T(1) - s * s;
    out[0] = (s + T(1)) * T(0.70710678118654752440);               // 1/sqrt2
    out[1] = T(-0.61237243569579452455) * c2;                      // 3/(2 sqrt6)
    out[2] = T(-0.79056941504209483300) * s * c2;                  // 5/(2 sqrt10)
    out[3] = T(0.23385358667337133659) * c2 * (T(5) * c2 - T(4));  // 7/(8 sqrt14)
}

/// Eq. 11: visibility vector v = v^-(pi/2) - v^-(sigma): visible for
/// elevations above sigma, given s = sin(sigma).
template <class T>
inline void nlpVisibleAbove(T s, T out[kNlpCount]) {
    const T c2 = T(1) - s * s;
    out[0] = (T(1) - s) * T(0.70710678118654752440);
    out[1] = T(0.61237243569579452455) * c2;
    out[2] = T(0.79056941504209483300) * s * c2;
    out[3] = T(-0.23385358667337133659) * c2 * (T(5) * c2 - T(4));
}

/// Visible between elevations with sines sLow <= sHigh (key lights restrict
/// Eq. 11 to the light's elevation interval, Section 6).
template <class T>
inline void nlpVisibleBetween(T sLow, T sHigh, T out[kNlpCount]) {
    T lo[kNlpCount], hi[kNlpCount];
    nlpOcclusion(sLow, lo);
    nlpOcclusion(sHigh, hi);
    for (int l = 0; l < kNlpCount; ++l) out[l] = hi[l] - lo[l];
}

/// sin(atan(t)) without trig; slopes are clamped to +-1e6 so t*t stays finite.
template <class T>
inline T sinFromSlope(T t) {
    t = t < T(-1e6) ? T(-1e6) : (t > T(1e6) ? T(1e6) : t);
    return t / std::sqrt(T(1) + t * t);
}

}  // namespace terrain::gi

#pragma once
// Quadrature of the normalised Phong lobe (Section 7's lobe, integrated
// exactly instead of through its order-4 SH factors): shared by the glossy
// reference (gi/reference_glossy_lobe.h) and the lobe-directed gather of the
// fast path (gi/glossy_lobe_gather.h).
//
// The lobe of exponent S about the unit vector R,
//   f(w) = (S + 1) / (2 pi) max(0, w . R)^S,  integral 1 over the sphere.
// The substitution t = (w . R)^(S + 1) turns its measure into a uniform one:
// int I f dw = int_0^1 dt int_0^{2 pi} I(w(t, psi)) dpsi / (2 pi), psi the
// azimuth about R. A midpoint rule with n rings in t and 2n azimuths in psi
// therefore integrates every exponent alike (the lobe's peak is absorbed by
// the substitution); each direction carries the weight 1 / (2 n^2).
//
// Every other ring is turned by half an azimuth step, so that the directions
// of neighbouring rings interleave instead of lining up on 2n spokes from R:
// the same rule in each variable, the directions spread more evenly about
// R; the lobe gather's error against the exact reference falls at every
// exponent (measured in README, "The lobe gather").

#include <cstddef>
#include <vector>

namespace terrain::gi {

/// Orthonormal frame (t, b) about the unit vector r.
void lobeFrame(const double r[3], double t[3], double b[3]);

/// c r + s (cp t + sp b): the direction at cosine c (sine s) from r and
/// azimuth (cp, sp) about it in the frame (t, b).
inline void lobeCombine(const double r[3], const double t[3], const double b[3], double c, double s, double cp,
                        double sp, double w[3]) {
    for (int k = 0; k < 3; ++k) w[k] = c * r[k] + s * (cp * t[k] + sp * b[k]);
}

/// Quadrature direction (ring i of n, azimuth j of 2n about R, odd rings
/// turned by half a step) of the Phong lobe of
/// exponent S about r (frame t, b from lobeFrame); each carries the weight
/// 1 / (2 n^2) of the lobe's unit mass.
void lobeDirection(const double r[3], const double t[3], const double b[3], double S, int n, int i, int j, double w[3]);

/// lobeDirection's directions with their cosines and sines kept for one
/// (S, n): a gather that evaluates the lobes of many receivers of the same
/// exponent computes them once (set is free while S and n do not change).
/// The same values as lobeDirection's, bit for bit.
class LobeQuadrature {
public:
    void set(double S, int n);
    int rings() const { return n_; }
    /// The cosine of the angle from R of the ring farthest from it: every
    /// direction lies within that angle.
    double widestCos() const { return ringCos_.front(); }
    void direction(const double r[3], const double t[3], const double b[3], int i, int j, double w[3]) const {
        const auto ii = static_cast<std::size_t>(i);
        const auto jj = static_cast<std::size_t>(i * 2 * n_ + j);
        lobeCombine(r, t, b, ringCos_[ii], ringSin_[ii], psiCos_[jj], psiSin_[jj], w);
    }

private:
    double S_ = -1.0;
    int n_ = 0;
    std::vector<double> ringCos_, ringSin_;  // n rings
    std::vector<double> psiCos_, psiSin_;    // ring by ring, its 2n azimuths
};

}  // namespace terrain::gi

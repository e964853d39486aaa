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
// azimuth about R. With rho^2 = 1 - t that is the uniform measure of the unit
// disk (rho, psi), whatever the exponent (the lobe's peak is absorbed by the
// substitution), and a quadrature of the disk serves every lobe.
//
// The rule (LobeLayout): rings about R, each holding directions evenly
// spaced in psi, every direction with the same weight 1 / N. A ring's slab of
// t is its share of the N directions, its directions at the slab's midpoint
// in t (a midpoint rule in each variable). Every other ring is turned by half
// of its own azimuth step, so that neighbouring rings interleave instead of
// lining up on spokes from R.
// - LobeLayout::uniform(n): n rings of 2n directions each, equal slabs (the
//   glossy reference's, n = 12 by default).
// - LobeLayout::growing(n, k): the i-th ring from R (i = 1..n) holds i k
//   directions, as many as its circumference on the disk asks for: cells
//   about as wide as they are deep, where the uniform rule's outer cells are
//   several times wider than deep. At equal count the gather is a little
//   less accurate with it (README, "Fewer rays") but faster: the growing
//   rule's outer ring lies nearer R (t = 1/3 at n = 2 against 1 / (2n) for
//   the uniform one), so fewer of its rays walk far along the ground. The
//   gather's default is growing(2, 5).

#include <cstddef>
#include <vector>

namespace terrain::gi {

/// Where a lobe quadrature puts its directions (see above): `rings` rings,
/// counted from the one farthest from R (ring 0); the ring nearest R holds
/// `innermost` directions and each ring outwards `growth` more.
struct LobeLayout {
    int rings = 1, innermost = 2, growth = 0;
    static LobeLayout uniform(int n) { return {n, 2 * n, 0}; }
    static LobeLayout growing(int n, int k) { return {n, k, k}; }
    /// Directions on ring i (0: the farthest from R).
    int ringDirections(int i) const { return innermost + growth * (rings - 1 - i); }
    /// Directions on the rings before ring i, and (i = rings) on all of them.
    int directionsBefore(int i) const { return i * innermost + growth * (i * (rings - 1) - i * (i - 1) / 2); }
    int directions() const { return directionsBefore(rings); }
    bool operator==(const LobeLayout&) const = default;
};

/// Orthonormal frame (t, b) about the unit vector r.
void lobeFrame(const double r[3], double t[3], double b[3]);

/// c r + s (cp t + sp b): the direction at cosine c (sine s) from r and
/// azimuth (cp, sp) about it in the frame (t, b).
inline void lobeCombine(const double r[3], const double t[3], const double b[3], double c, double s, double cp,
                        double sp, double w[3]) {
    for (int k = 0; k < 3; ++k) w[k] = c * r[k] + s * (cp * t[k] + sp * b[k]);
}

/// Quadrature direction j of ring i of `layout` (see above) of the Phong
/// lobe of exponent S about r (frame t, b from lobeFrame); each carries the
/// weight 1 / layout.directions() of the lobe's unit mass.
void lobeDirection(const double r[3], const double t[3], const double b[3], double S, const LobeLayout& layout, int i,
                   int j, double w[3]);

/// lobeDirection's directions with their cosines and sines kept for one
/// (S, layout), numbered ring by ring: a gather that evaluates the lobes of
/// many receivers of the same exponent computes them once (set is free while
/// S and the layout do not change). The same values as lobeDirection's, bit
/// for bit.
class LobeQuadrature {
public:
    void set(double S, const LobeLayout& layout);
    int directions() const { return static_cast<int>(psiCos_.size()); }
    /// The cosine of the angle from R of the ring farthest from it: every
    /// direction lies within that angle.
    double widestCos() const { return ringCos_.front(); }
    /// Direction d (ring by ring, from ring 0).
    void direction(const double r[3], const double t[3], const double b[3], int d, double w[3]) const {
        const auto k = static_cast<std::size_t>(d);
        const auto ring = static_cast<std::size_t>(ringOf_[k]);
        lobeCombine(r, t, b, ringCos_[ring], ringSin_[ring], psiCos_[k], psiSin_[k], w);
    }

private:
    double S_ = -1.0;
    LobeLayout layout_{0, 0, 0};
    std::vector<double> ringCos_, ringSin_;  // per ring
    std::vector<double> psiCos_, psiSin_;    // per direction, ring by ring
    std::vector<int> ringOf_;                // per direction
};

}  // namespace terrain::gi

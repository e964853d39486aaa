#pragma once
// A diagnosis for `terrain_bench gi-bound-diagnosis`: the weight with which
// a move of one azimuth's horizon changes the ambient map, where it moves
// and under which normals, in place of the one weight gi/change_bound.h
// takes for every elevation and normal.
//
// gi/change_bound.h: moving sin(sigma) of azimuth sample j from u to u'
// changes the ambient by the integral over phi of beta_j(phi) times the
// integral from u to u' of g(z, phi), g the degree-3 Legendre projection in
// z of k(N . w(z, phi)), k(x) = (15 x^2 + 16 x + 3) / (32 pi) the clamped
// cosine's bands 0..2 over pi, w the direction of elevation asin z along
// phi. The frames bound |g| by its largest value over every z, phi and N
// (kShadePerSlope = 2 pi max|g|, rounded up). But N . w = N_z z + h
// sqrt(1 - z^2), h = N_x cos phi + N_y sin phi, so g depends on the normal
// only through (N_z, h), and near the tangent plane (N . w ~ 0) it is about
// a tenth of its largest value. Here the four Legendre coefficients of g are
// tabulated over (N_z, h) and interpolated, and |g| is maximised over a
// band of z exactly (a cubic): an estimate of the tighter weight, not a
// bound (the table's interpolation and the sampled normals and azimuths are
// not covered).
#include <array>
#include <vector>

namespace terrain::bench {

class ElevationWeight {
public:
    ElevationWeight();
    /// The largest |g(z)| for z in [z0, z1] under the normal with vertical
    /// component nz (> 0) and horizontal component h along the azimuth.
    double largest(double nz, double h, double z0, double z1) const;

private:
    static constexpr int kNz = 129, kH = 257;
    std::vector<std::array<double, 4>> table_;  // Legendre coefficients at (nz, h) grid points
    std::array<double, 4> coefficients(double nz, double h) const;
    static double largestOf(const std::array<double, 4>& c, double z0, double z1);
};

}  // namespace terrain::bench

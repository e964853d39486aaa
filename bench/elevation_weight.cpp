#include "bench/elevation_weight.h"

#include <algorithm>
#include <cmath>

#include "gi/sh.h"

namespace terrain::bench {
namespace {

// The Legendre polynomials P_0..P_3 at z.
std::array<double, 4> legendreP(double z) {
    return {1.0, z, 0.5 * (3.0 * z * z - 1.0), 0.5 * (5.0 * z * z * z - 3.0 * z)};
}

// The clamped cosine's bands 0..2 over pi at x = N . w, from its zonal
// coefficients: sum_l z_l sqrt((2l + 1) / (4 pi)) P_l(x) / pi.
double bandLimitedCosine(double x) {
    const double* zh = gi::lambertZonal();
    const std::array<double, 4> p = legendreP(x);
    double k = 0.0;
    for (int l = 0; l < 3; ++l)
        k += zh[l] * std::sqrt((2.0 * l + 1.0) / (4.0 * gi::kPi)) * p[static_cast<std::size_t>(l)];
    return k / gi::kPi;
}

// g(z) = sum_n c_n P_n(z), n = 0..3.
double legendreSum(const std::array<double, 4>& c, double z) {
    const std::array<double, 4> p = legendreP(z);
    return c[0] * p[0] + c[1] * p[1] + c[2] * p[2] + c[3] * p[3];
}

}  // namespace

ElevationWeight::ElevationWeight() {
    constexpr int kNodes = 64;
    double zs[kNodes], ws[kNodes];
    gi::gaussLegendre(kNodes, zs, ws);
    table_.resize(static_cast<std::size_t>(kNz) * kH);
    for (int a = 0; a < kNz; ++a)
        for (int b = 0; b < kH; ++b) {
            const double nz = static_cast<double>(a) / (kNz - 1), h = -1.0 + 2.0 * b / (kH - 1);
            std::array<double, 4> c{};
            for (int i = 0; i < kNodes; ++i) {
                const double z = zs[i], f = bandLimitedCosine(nz * z + h * std::sqrt(1.0 - z * z));
                const std::array<double, 4> p = legendreP(z);
                for (std::size_t n = 0; n < 4; ++n)
                    c[n] += ws[i] * f * p[n] * (2.0 * static_cast<double>(n) + 1.0) / 2.0;
            }
            table_[static_cast<std::size_t>(a) * kH + b] = c;
        }
}

std::array<double, 4> ElevationWeight::coefficients(double nz, double h) const {
    const double fa = std::clamp(nz, 0.0, 1.0) * (kNz - 1), fb = (std::clamp(h, -1.0, 1.0) + 1.0) * 0.5 * (kH - 1);
    const int a = std::min(static_cast<int>(fa), kNz - 2), b = std::min(static_cast<int>(fb), kH - 2);
    const double ta = fa - a, tb = fb - b;
    std::array<double, 4> c{};
    for (int da = 0; da < 2; ++da)
        for (int db = 0; db < 2; ++db) {
            const double w = (da ? ta : 1.0 - ta) * (db ? tb : 1.0 - tb);
            const std::array<double, 4>& t = table_[static_cast<std::size_t>(a + da) * kH + b + db];
            for (std::size_t n = 0; n < 4; ++n) c[n] += w * t[n];
        }
    return c;
}

double ElevationWeight::largest(double nz, double h, double z0, double z1) const {
    return largestOf(coefficients(nz, h), z0, z1);
}

double ElevationWeight::largestOf(const std::array<double, 4>& c, double z0, double z1) {
    if (z0 > z1) std::swap(z0, z1);
    z0 = std::clamp(z0, -1.0, 1.0);
    z1 = std::clamp(z1, -1.0, 1.0);
    double best = std::max(std::fabs(legendreSum(c, z0)), std::fabs(legendreSum(c, z1)));
    // interior extrema: g'(z) = A z^2 + B z + C = 0
    const double A = 7.5 * c[3], B = 3.0 * c[2], C = c[1] - 1.5 * c[3];
    const auto consider = [&](double z) {
        if (z > z0 && z < z1) best = std::max(best, std::fabs(legendreSum(c, z)));
    };
    if (std::fabs(A) > 1e-300) {
        const double disc = B * B - 4.0 * A * C;
        if (disc >= 0.0) {
            consider((-B + std::sqrt(disc)) / (2.0 * A));
            consider((-B - std::sqrt(disc)) / (2.0 * A));
        }
    } else if (std::fabs(B) > 1e-300) {
        consider(-C / B);
    }
    return best;
}

}  // namespace terrain::bench

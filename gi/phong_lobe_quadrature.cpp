#include "gi/phong_lobe_quadrature.h"

#include <algorithm>
#include <cmath>

#include "gi/sh.h"

namespace terrain::gi {

void lobeFrame(const double r[3], double t[3], double b[3]) {
    // the axis least aligned with r gives a well-conditioned cross product
    const double ax = std::fabs(r[0]), ay = std::fabs(r[1]), az = std::fabs(r[2]);
    const double e[3] = {ax <= ay && ax <= az ? 1.0 : 0.0, ay < ax && ay <= az ? 1.0 : 0.0,
                         az < ax && az < ay ? 1.0 : 0.0};
    t[0] = r[1] * e[2] - r[2] * e[1];
    t[1] = r[2] * e[0] - r[0] * e[2];
    t[2] = r[0] * e[1] - r[1] * e[0];
    const double len = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (int k = 0; k < 3; ++k) t[k] /= len;
    b[0] = r[1] * t[2] - r[2] * t[1];
    b[1] = r[2] * t[0] - r[0] * t[2];
    b[2] = r[0] * t[1] - r[1] * t[0];
}

namespace {

// Ring i of n: the midpoint of [i / n, (i + 1) / n] in t = cos^(S + 1).
double ringCosine(double S, int n, int i) {
    const double tm = (i + 0.5) / n;
    return std::exp(std::log(tm) / (S + 1.0));
}

double ringSine(double c) { return std::sqrt(std::max(0.0, 1.0 - c * c)); }

// Azimuth j of the 2n about R on ring i (odd rings turned by half a step).
double azimuthAngle(int n, int i, int j) { return kPi * (j + 0.5 + 0.5 * (i % 2)) / n; }

}  // namespace

void lobeDirection(const double r[3], const double t[3], const double b[3], double S, int n, int i, int j,
                   double w[3]) {
    const double c = ringCosine(S, n, i), psi = azimuthAngle(n, i, j);
    lobeCombine(r, t, b, c, ringSine(c), std::cos(psi), std::sin(psi), w);
}

void LobeQuadrature::set(double S, int n) {
    if (n != n_) {
        n_ = n;
        S_ = -1.0;
        psiCos_.resize(static_cast<std::size_t>(2 * n * n));
        psiSin_.resize(static_cast<std::size_t>(2 * n * n));
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < 2 * n; ++j) {
                const auto at = static_cast<std::size_t>(i * 2 * n + j);
                psiCos_[at] = std::cos(azimuthAngle(n, i, j));
                psiSin_[at] = std::sin(azimuthAngle(n, i, j));
            }
    }
    if (S == S_) return;
    S_ = S;
    ringCos_.resize(static_cast<std::size_t>(n));
    ringSin_.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
        ringCos_[static_cast<std::size_t>(i)] = ringCosine(S, n, i);
        ringSin_[static_cast<std::size_t>(i)] = ringSine(ringCos_[static_cast<std::size_t>(i)]);
    }
}

}  // namespace terrain::gi

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

// Ring i's slab of t is its share of the directions (ring 0 from t = 0, the
// farthest from R); its directions lie at the slab's midpoint.
double ringCosine(double S, const LobeLayout& layout, int i) {
    const double tm =
        static_cast<double>(layout.directionsBefore(i) + layout.directionsBefore(i + 1)) / (2.0 * layout.directions());
    return std::exp(std::log(tm) / (S + 1.0));
}

double ringSine(double c) { return std::sqrt(std::max(0.0, 1.0 - c * c)); }

// Azimuth j about R of the c directions of ring i: half a step from psi = 0,
// odd rings turned by another half step.
double azimuthAngle(const LobeLayout& layout, int i, int j) {
    return kPi * (2 * j + 1 + i % 2) / layout.ringDirections(i);
}

}  // namespace

void lobeDirection(const double r[3], const double t[3], const double b[3], double S, const LobeLayout& layout, int i,
                   int j, double w[3]) {
    const double c = ringCosine(S, layout, i), psi = azimuthAngle(layout, i, j);
    lobeCombine(r, t, b, c, ringSine(c), std::cos(psi), std::sin(psi), w);
}

void LobeQuadrature::set(double S, const LobeLayout& layout) {
    if (!(layout == layout_)) {
        layout_ = layout;
        S_ = -1.0;
        psiCos_.clear();
        psiSin_.clear();
        ringOf_.clear();
        for (int i = 0; i < layout.rings; ++i)
            for (int j = 0; j < layout.ringDirections(i); ++j) {
                psiCos_.push_back(std::cos(azimuthAngle(layout, i, j)));
                psiSin_.push_back(std::sin(azimuthAngle(layout, i, j)));
                ringOf_.push_back(i);
            }
    }
    if (S == S_) return;
    S_ = S;
    ringCos_.resize(static_cast<std::size_t>(layout.rings));
    ringSin_.resize(static_cast<std::size_t>(layout.rings));
    for (int i = 0; i < layout.rings; ++i) {
        ringCos_[static_cast<std::size_t>(i)] = ringCosine(S, layout, i);
        ringSin_[static_cast<std::size_t>(i)] = ringSine(ringCos_[static_cast<std::size_t>(i)]);
    }
}

}  // namespace terrain::gi

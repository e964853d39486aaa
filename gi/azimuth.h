#pragma once
// A fast azimuth for the glossy gathers' per-ray and per-hit directions.
#include <algorithm>
#include <cmath>

#include "gi/sh.h"

namespace terrain::gi {

/// The azimuth of (x, y) in [0, 2 pi), within 1e-5 radians: the rays' split
/// between two global azimuths needs no more (a weight moves by 1e-5 / the
/// azimuths' spacing), and libm's atan2 was a tenth of the lobe gather's
/// time. atan on [0, 1] by Abramowitz & Stegun (1964), Eq. 4.4.49, then the
/// octant.
inline double azimuthOf(double x, double y) {
    const double ax = std::fabs(x), ay = std::fabs(y);
    const double lo = std::min(ax, ay), hi = std::max(ax, ay);
    const double q = hi > 0.0 ? lo / hi : 0.0, q2 = q * q;
    double a = q * (0.9998660 + q2 * (-0.3302995 + q2 * (0.1801410 + q2 * (-0.0851330 + q2 * 0.0208351))));
    a = ay > ax ? 0.5 * kPi - a : a;
    a = x < 0.0 ? kPi - a : a;
    a = y < 0.0 ? 2.0 * kPi - a : a;
    return a >= 2.0 * kPi ? 0.0 : a;
}

}  // namespace terrain::gi

#pragma once
// The exact Phong exit radiance of the glossy reference (gi/reference_gi.h,
// renderReferenceGlossy): the sky's radiance through a point's exact
// visibility, integrated against the point's Phong lobe by quadrature, with
// no SH projection anywhere (so the reference can measure the fast path's
// order-4 SH ringing and blur).
//
// The lobe (Section 7): the normalised Phong lobe of exponent S about the
// reflection R of the outgoing direction,
//   f(w) = (S + 1) / (2 pi) max(0, w . R)^S,  integral 1 over the sphere,
// the lobe whose SH factors phongLobeFactors approximates by e^{-l^2/(2S)}.
// The exit radiance's Phong part is int I(w) f(w) dw (no cosine: the fast
// path's lobe is convolved with the incident radiance alone).
//
// The incident radiance I(w): the sky's SH radiance evaluated in direction w
// (no projection of the visible part) where w is above the point's tangent
// plane and above its horizon, 0 elsewhere. Horizons: the exact maximum
// blocking slope of gi/reference (referenceMaxSlope) at every grid point for
// M azimuths phi_a = 2 pi (a + 0.5) / M; between azimuths linear, at a first
// hit between grid points bilinear.
//
// Quadrature: gi/phong_lobe_quadrature.h (rings in t = (w . R)^(S + 1),
// directions evenly spaced in the azimuth about R on each); the error comes
// from the horizon edge and the sky's variation only. The convergence is
// tested by doubling the rings.
#include <vector>

#include "core/grid.h"
#include "gi/lights.h"
#include "gi/phong_lobe_quadrature.h"

namespace terrain::gi {

/// Exact horizons of every grid point: the maximum blocking slope
/// (referenceMaxSlope, kNoBlocker where nothing blocks) at M azimuths.
struct SkyHorizons {
    int nx = 0, ny = 0, azimuths = 0;
    std::vector<float> slope;  // ((y * nx) + x) * azimuths + a
    /// Blocking slope at (px, py) cells in direction phi: bilinear between
    /// grid points, linear between azimuths.
    double at(float px, float py, double phi) const;
};

void buildSkyHorizons(ConstGridView heights, float cellSize, int azimuths, SkyHorizons& out);

/// True when direction w is above the tangent plane of normal n and above the
/// horizon at (px, py).
bool skyVisible(const SkyHorizons& hz, float px, float py, const double n[3], const double w[3]);

/// Phong part of the exit radiance (RGB) at (px, py) with unit normal n
/// towards the direction whose reflection about n is r: int I f dw over the
/// sky `lighting` through the exact visibility, by the quadrature `layout`.
void exactLobeRadiance(const SkyHorizons& hz, const ShRgb& lighting, float px, float py, const double n[3],
                       const double r[3], double S, const LobeLayout& layout, double out[3]);

}  // namespace terrain::gi

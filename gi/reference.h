#pragma once
// Ground truth (Section 8, Fig. 10): exact visibility by marching the full
// resolution bilinear height field, dense azimuths, exact elevation
// integrals, lighting evaluated from the same order-4 SH, exact BRDF
// integration.
//
// Per texel and per azimuth phi_a = 2 pi (a + 0.5) / M (each standing for a
// wedge of 2 pi / M), the ray from the texel is marched through the bilinear
// height field, sampled at every crossing of a grid line (where the bilinear
// surface is exactly linear along the line) and at the midpoint between
// crossings; the largest blocking slope is kept. The march ends at the domain
// border (nothing outside the height field blocks, as in the fast path) or
// once no height in the grid could beat the current slope.
// With lo = max(omega_max, elevation of the tangent plane), the elevation
// integral of (N . d) cos(omega) is closed-form for the ambient map, and for
// SH lighting the separable Y_i = A_i(sin omega) T_i(phi) reduces it to two
// 1-D functions of lo per coefficient, tabulated once by Gauss-Legendre
// quadrature.
// Normals are the same central-difference normals as the fast path uses.
#include <array>
#include <atomic>

#include "core/grid.h"
#include "gi/lights.h"
#include "gi/shading.h"

namespace terrain::gi {

struct ReferenceSettings {
    int azimuths = 256;     // M (>= 256 for the accuracy claims)
    int border = 0;         // texels left out at each border (their outputs are 0)
    int stride = 1;         // compute every stride-th texel in x and y (others 0)
    bool progress = false;  // print progress to stdout on long runs
};

struct ReferenceResult {
    Grid ambient;             // normal-weighted sky-view factor (uniform unit sky)
    std::array<Grid, 3> rgb;  // Lambert shade under `lighting` (when given)
};

/// Renders the ground truth. `lighting` may be null (ambient only).
void renderReference(ConstGridView heights, float cellSize, const ShRgb* lighting, const AlbedoMap* albedo,
                     const ReferenceSettings& settings, ReferenceResult& out);

/// The ground truth of the analytic sky's Lambert shade (out.rgb; out.ambient
/// as renderReference), integrating its radiance function, not its SH
/// projection: above the horizontal L(w) = horizon + (zenith - horizon) sin w,
/// below it `ground` (gi::sunSkyLight's gradient). Per azimuth, over the
/// visible elevations [lo, pi/2] (lo = max(horizon, tangent plane)), the
/// integral of L(w) (N . d) cos w is closed form:
///   int cos^2 = w/2 + sin 2w / 4,   int sin cos = sin^2 w / 2,
///   int sin cos^2 = -cos^3 w / 3,   int sin^2 cos = sin^3 w / 3.
/// Throws InputError when `sky` has a sun lobe (integrate the sun as a key
/// light: addReferenceKeyLight, gi/reference_gi.h).
void renderReferenceSkyGradient(ConstGridView heights, float cellSize, const SunSkySettings& sky,
                                const AlbedoMap* albedo, const ReferenceSettings& settings, ReferenceResult& out);

/// Exact maximum blocking slope of the bilinear height field from grid point
/// (x, y) along unit direction (c, s) (cells), or kNoBlocker when the ray
/// leaves the domain at once. heightMax: the grid's maximum (early exit).
double referenceMaxSlope(ConstGridView heights, float cellSize, int x, int y, double c, double s, double heightMax);

}  // namespace terrain::gi

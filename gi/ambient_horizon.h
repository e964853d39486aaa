#pragma once
// The ambient map (normal-weighted sky-view factor: irradiance / pi under a
// uniform unit sky) integrated exactly above each azimuth's horizon, instead
// of through the order-4 SH product lam(N) . V (Nowrouzezahrai & Snyder 2009,
// Section 7), whose truncation is a floor the ambient error cannot go below.
//
// Along azimuth phi the sky is visible above sigma = max(horizon, tangent
// plane) (the tangent plane's elevation atan(g), g the directional derivative
// of the height: below it N . w < 0). With w = (cos t cos phi, cos t sin phi,
// sin t) and N = (-gx, -gy, 1) / n, n = sqrt(1 + gx^2 + gy^2), the
// cosine-weighted integral over elevation is closed form:
//
//   I(phi) = int_sigma^{pi/2} (N . w) cos t dt
//          = [ -g (pi/2 - sigma - sin sigma cos sigma) + cos^2 sigma ] / (2 n)
//
// and the ambient is (1 / pi) int I(phi) dphi, by the midpoint rule over the
// scan's m azimuths: (2 / m) sum_j I(phi_j). A flat open plane gives exactly
// 1; the only errors left are the horizons' (pyramid, step sampling) and the
// azimuthal sampling.
//
// Sub-sampling (Fig. 7): the horizon slope of each receiver is first raised
// to its lowest tangent slope (the footprint box's, as the SH visibility
// does, or the receiver's own), interpolated bilinearly to the texel, and
// raised to the texel's own tangent slope there, and to the texel's own near
// field (gi/near_field.h).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/grid.h"
#include "gi/lights.h"
#include "gi/near_field.h"
#include "gi/shading.h"
#include "gi/texel_runs.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// Which formula gives the ambient map.
enum class AmbientMethod {
    Horizons,   // exact per-azimuth integral above the scanned horizons (engine)
    ShProduct,  // lam(N) . V_env / pi, order-4 SH (paper, Section 7)
};

/// What the exact ambient reads: the environment scan's horizons
/// (VisibilityField::maxSlope) and azimuths (cos, sin pairs), the full
/// resolution gradients, and the footprint boxes when sub-sampling uses them.
struct AmbientInputs {
    ConstGridView gradX, gradY;
    ConstGridView heights;  // full resolution (read for the near field when subsample > 1)
    float cellSize = 1.0f;  // metres
    int subsample = 1;
    const VisibilityField* env = nullptr;
    std::span<const float> cosSin;            // azimuths x 2
    const FootprintBox* footprint = nullptr;  // null: the receivers' own tangent planes
};

/// Buffers of the computation, reused across frames.
struct AmbientScratch {
    std::vector<float> rows;               // per worker slot: row buffers and the raised receiver rows
    std::vector<ReceiverLerp> columns;     // per texel column: the receivers it lies between
    std::vector<NearFieldStep> nearSteps;  // azimuths x subsample
    std::vector<int> busyBlocks;           // the row blocks with texels to do
};

/// Adds the light of a sky of constant radiance `radiance` (RGB) to a
/// Lambert shade: albedo x radiance x ambient at each texel (the ambient is
/// the cosine-weighted visible sky / pi). With the ambient from the horizons
/// the environment's constant part (its band-0 SH coefficient) is lit
/// exactly this way and only the rest goes through the SH product, whose
/// truncation error then scales with the sky's variation, not its level.
/// `runs` as for ambientFromHorizons.
void addConstantSky(const Grid& ambient, const float radiance[3], const AlbedoMap* albedo, std::array<Grid, 3>& shade,
                    const TexelRuns* runs = nullptr);

/// What ambientFromHorizons writes: the ambient map and, when `below` and
/// `rising` are given, the two parts of it that light the analytic sky
/// (SkyGradient, gi/lights.h) exactly. With a = max(sigma, 0), per azimuth
///   below:  the integral of (N . w) cos t over [sigma, 0] (0 when sigma >= 0),
///   rising: the integral of sin t (N . w) cos t over [a, pi/2]
///         = [1 - sin^3 a - g cos^3 a] / (3 n),
/// each normalised as the ambient; the sky's Lambert shade is then
///   albedo [horizon (ambient - below) + ground below + (zenith - horizon) rising].
struct AmbientOutputs {
    Grid& ambient;
    Grid* below = nullptr;
    Grid* rising = nullptr;
};

/// Writes the ambient map and the parts asked for (resized to the gradients'
/// size). `runs` (gi/texel_runs.h; null: every texel): only those texels
/// are computed, the others keep what the maps hold. Each texel's values do
/// not depend on the runs, the thread count, or whether the parts are
/// computed.
void ambientFromHorizons(const AmbientInputs& in, const AmbientOutputs& out, AmbientScratch& scratch,
                         const TexelRuns* runs = nullptr);

/// Adds the Lambert shade of the analytic sky from the ambient's parts
/// (AmbientOutputs with below and rising). `runs` as for ambientFromHorizons.
void addGradientSky(const AmbientOutputs& parts, const SkyGradient& sky, const AlbedoMap* albedo,
                    std::array<Grid, 3>& shade, const TexelRuns* runs = nullptr);

}  // namespace terrain::gi

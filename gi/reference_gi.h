#pragma once
// Ground truth with indirect light (issue "GI part 2"; paper 000's first-hit
// gathering with the Method of Dependent Tests: one fixed direction set shared
// by every texel).
//
// Bounce 0 is the direct exit radiance of the exact reference (gi/reference.h:
// exact visibility, exact elevation integrals, the same order-4 SH lighting).
// Bounce b >= 1: for every texel p and every direction w_k of the fixed set
// with N . w_k > 0, the ray is marched through the full-resolution bilinear
// height field to its first hit q_k; the irradiance is
//   E_b(p) = sum_k L_{b-1}(q_k) (N . w_k) 4 pi / K,
// with L_{b-1} the previous bounce's diffuse exit radiance, bilinear at q_k,
// and L_b = albedo(p) / pi * E_b. Rays that leave the domain or rise above the
// highest point escape (they see the sky, which bounce 0 already counted).
// Indirect = sum of L_b over b = 1..bounces; total = direct + indirect.
#include <array>

#include "gi/lights.h"
#include "gi/reference.h"
#include "gi/shading.h"
#include "sim/grid.h"

namespace terrain::gi {

struct ReferenceGiSettings {
    int directions = 2048;    // K: fixed set over the sphere (Fibonacci), shared by every texel
    int bounces = 1;          // indirect bounces after the direct one
    int azimuths = 256;       // of the direct (bounce 0) reference
    float marchStep = 0.5f;   // march step along the ray, in cells
    bool progress = false;    // progress on stderr
};

struct ReferenceGiResult {
    std::array<Grid, 3> direct;    // bounce 0 exit radiance (Lambert, albedo applied)
    std::array<Grid, 3> indirect;  // sum of bounces 1..B
    std::array<Grid, 3> total;     // direct + indirect
    Grid ambient;                  // direct-only normal-weighted sky-view factor
};

/// Renders the reference with indirect light. `lighting` holds every light
/// as SH (key lights folded in with keyLightSh). albedo may be null (1).
void renderReferenceGi(ConstGridView heights, float cellSize, const ShRgb& lighting, const AlbedoMap* albedo,
                       const ReferenceGiSettings& settings, ReferenceGiResult& out);

/// One gathering bounce: next(p) = albedo(p) / pi * sum_k prev(q_k) (N . w_k) 4 pi / K
/// over the fixed direction set (the rays' first hits q_k). next is resized.
void gatherReferenceBounce(ConstGridView heights, float cellSize, const std::array<Grid, 3>& prev,
                           const AlbedoMap* albedo, const ReferenceGiSettings& settings, std::array<Grid, 3>& next);

/// The fixed direction set: K unit vectors spread evenly over the sphere.
void referenceDirections(int count, std::vector<std::array<float, 3>>& out);

}  // namespace terrain::gi

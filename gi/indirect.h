#pragma once
// Indirect light on the fast path (Sections 3-7; Eqs. 6-8, 12, 17-21).
//
// For every receiver and azimuth phi_j the scan walks the height pyramid's
// exponential steps (Eq. 14) and keeps the casting set (Eq. 17): the steps
// whose blocking slope beats every earlier one. Each member t_i carries the
// previous bounce's exit radiance u(t_i), read from the radiance pyramid
// (gi/radiance_pyramid.h) at the same step position. Radiance is piecewise
// constant in elevation (Eq. 8): u(t_i) over [omega(t_(i-1)), omega(t_i)),
// with omega(t_(-1)) = omega_min. Every segment is clamped to
// [omega_min, pi/2] (below the tangent plane nothing reaches the receiver),
// and its NLP projection is u(t_i) (vbar(c_i) - vbar(c_(i-1))), c the clamped
// angles: summed, this is Eq. 12. Since vbar is a polynomial in s = sin(omega)
// (Eq. 10's closed form), the kernel accumulates u * Delta(s^p), p = 1..4, and
// converts to the 4 NLP coefficients once per receiver and azimuth:
//   u_0 = k0 A1, u_1 = k1 A2, u_2 = k2 (A3 - A1), u_3 = k3 (5 A4 - 6 A2).
// U per receiver and channel comes from the same folded wedge operator as the
// environment visibility (Eqs. 19-21). The incident radiance is U itself; it is
// shaded like direct light (gi/shading.h: SH vectors interpolated from the
// receiver grid, dotted with the BRDF rotated to each full-resolution normal),
// giving the bounce's exit radiance L_b. Bounce b + 1 builds its radiance
// pyramid from L_b (Section 7); the result accumulates L_1 + ... + L_B.
//
// Glossy surfaces (IndirectSettings::glossy): ScalarPyramid forwards the
// scalar shade (diffuse + glossy towards the viewer, per
// ShadingSettings::brdf) to the next bounce's RGB pyramid: the single-pyramid
// approximation of Fig. 5 (right). VectorPyramid filters SH exit-radiance
// vectors and evaluates them towards each receiver (Fig. 5 middle):
// gi/indirect_glossy.h.
//
// Heights equal up to float rounding must not count as blockers (a flat
// plane gets exactly no indirect light): a sample counts in the casting set
// only when it rises above the receiver's height by more than 2^-20 |h0|
// (a few ulp), which is subtracted from every height difference.
//
// Schedule: like gi/visibility: a per-bounce step table, fixed row blocks in
// parallel, each row's azimuths serially, every receiver written by one block:
// bit-identical for any thread count; no allocation after the first frame of
// a given size and settings.
#include <array>
#include <vector>

#include "gi/indirect_glossy.h"
#include "gi/pyramid.h"
#include "gi/radiance_pyramid.h"
#include "gi/shading.h"
#include "gi/visibility.h"
#include "gi/wedge.h"
#include "sim/grid.h"

namespace terrain::gi {

enum class GlossyIndirect {
    ScalarPyramid,  // one RGB pyramid of the scalar shade (diffuse + glossy towards the viewer), Fig. 5 right
    VectorPyramid,  // a pyramid of SH exit-radiance vectors, evaluated towards each receiver (Fig. 5 middle; gi/indirect_glossy.h)
};

struct IndirectSettings {
    int bounces = 0;                   // 0: direct light only
    RadiancePyramidSettings radiance;  // k_u = 4, o_u = 2
    bool amortise = false;             // Section 7: alternate direct / indirect on static geometry
    GlossyIndirect glossy = GlossyIndirect::ScalarPyramid;
    // Lambert receivers only (ignored for other BRDFs): irradiance from the
    // casting-set segments with the exact clamped cosine instead of Eq. 12 +
    // the wedge operator + the order-4 SH Lambert kernel. Per receiver and
    // channel the scan accumulates A = sum_j dphi d_j sum u Delta((w + sin w cos w) / 2)
    // and B = sum_j dphi sum u Delta(sin^2 w / 2) (box weights in azimuth);
    // E = A . N_h + B N_z at each full-resolution normal N, written into U's
    // band-1 planes so that gi/shading's Lambert path evaluates exactly that.
    // Measured (bench_gi_indirect --quick, 96^2 crops, 1 bounce): at 1x
    // the indirect error drops (alps 8.6 -> 6.6 %, erosion 22.3 -> 7.1 %), at
    // 2x it rises (alps 17.1 -> 30.2 %, bias -17 %): the linear E(N) misses the
    // light between the receiver's and a texel's tangent planes where the
    // full-resolution normal departs from the receiver's. Off by default.
    bool exactCosine = false;
    // With exactCosine: E evaluated at the receiver's own normal and
    // interpolated as a scalar (band 0); no full-resolution normal detail
    // (2x alps 20.7 %, bias -4.3 %).
    bool exactCosineReceiverNormal = false;
};

struct IndirectTimings {
    double pyramid = 0.0, scan = 0.0, shading = 0.0, total = 0.0;
};

/// Per-block scratch of the indirect scan.
struct IndirectScratch {
    std::vector<float> gx, gy, h0, margin;  // padded receiver row
    std::vector<float> nlp;                 // 3 channels x 4 NLP x padded row, one azimuth
    std::vector<float> moments;             // casting-set moments of one group (pass 1 -> pass 2)
    std::vector<int> list;                  // steps with a new casting-set member in the group
};

struct IndirectState {
    RadiancePyramid radiance;
    std::vector<ScanStep> heightSteps;   // azimuths x steps
    std::vector<ScanStep> radianceSteps; // channels x azimuths x steps
    std::vector<int> stepsPerColumn, stepsPerRow;
    std::vector<IndirectScratch> blocks;
    std::array<VisibilityField, 3> u;    // U per channel (16 SH planes at the receivers)
    std::array<ShadingLight, 3> lights;
    std::array<ShadeMaps, 2> bounceShade;  // exit radiance of the current / previous bounce
    std::array<Grid, 3> indirect;  // sum of bounces 1..B, full resolution
    std::array<Grid, 3> total;     // direct + indirect
    std::vector<double> bounceMean;  // mean exit radiance (RGB average) of each bounce
    IndirectTimings timings;
    GlossyIndirectState glossy;    // vector-pyramid buffers (GlossyIndirect::VectorPyramid)
};

/// Indirect light of `bounces` bounces over the frame's height pyramid.
/// direct: bounce 0's exit radiance (full resolution, albedo applied);
/// directShade: the direct shading it came from (its incident SH vectors),
/// needed by GlossyIndirect::VectorPyramid with a non-Lambert BRDF (without
/// it that case throws InputError).
void computeIndirect(const HeightPyramid& heights, ConstGridView gradX, ConstGridView gradY,
                     const FoldedWedgeOperator& op, const VisibilityField& envVisibility,
                     const std::array<Grid, 3>& direct, const AlbedoMap* albedo, const ShadingSettings& shading,
                     const IndirectSettings& settings, IndirectState& state, const ShadeMaps* directShade = nullptr);

/// Throws InputError when a setting is out of range.
void validateIndirectSettings(const IndirectSettings& s);

}  // namespace terrain::gi

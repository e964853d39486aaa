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
// giving the bounce's exit radiance L_b (the engine's Lambert default,
// LambertIndirect::BlockerRadiance, keeps no U: the exact irradiance at the
// receivers, and between them the blockers' mean radiance times each texel's
// occlusion, gi/blocker_radiance.h). Bounce b + 1 builds its radiance
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
// Speed: the kernel runs over 8 (AVX2) or 4 (SSE2) lanes, bit-identically
// (sim/simd.h), one receiver row at a time, step by step (each step's reads
// sweep one stretch of its field). A group of lanes stops walking once the
// field's highest height, seen from each lane's receiver at the current
// distance, can no longer beat that lane's running maximum (no member can
// follow; results unchanged). With ExactAtReceivers at 1x only the exact
// moment is computed (every texel is a receiver).
//
// Schedule: like gi/visibility: a per-bounce step table, fixed blocks of
// kIndirectRows receiver rows in parallel; within a block azimuth by azimuth,
// the block's rows one after the other (consecutive rows read neighbouring
// rows of every level, which stay in cache), every receiver written by one
// block: bit-identical for any thread count; no allocation after the first
// frame of a given size and settings.
#include <array>
#include <functional>
#include <vector>

#include "gi/blocker_radiance.h"
#include "gi/indirect_glossy.h"
#include "gi/pyramid.h"
#include "gi/radiance_pyramid.h"
#include "gi/shading.h"
#include "gi/visibility.h"
#include "gi/wedge.h"
#include "core/grid.h"

namespace terrain::gi {

enum class GlossyIndirect {
    ScalarPyramid,  // one RGB pyramid of the scalar shade (diffuse + glossy towards the viewer), Fig. 5 right
    VectorPyramid,  // a pyramid of SH exit-radiance vectors, evaluated towards each receiver (Fig. 5 middle; gi/indirect_glossy.h)
};

// How Lambert receivers turn their casting sets into irradiance.
enum class LambertIndirect {
    // Eq. 12 + the folded wedge operator + the order-4 SH clamped cosine (the
    // paper). The SH kernel over-weights light near the horizon (k(0) = 0.094):
    // +21 % indirect bias on an eroded terrain (bench/results/gi_indirect_diagnosis.md).
    ShKernel,
    // The same U, with its band-0 coefficient shifted per receiver so that the
    // shade at the receiver's own normal is the exact clamped-cosine
    // irradiance of its casting sets, E = sum_j dphi sum_i u_i Delta(f2 - g_j f1)
    // / |n| (f1 = (w + sin w cos w) / 2, f2 = sin^2 w / 2 at the clamped
    // segment ends, g_j the tangent slope along azimuth j, box weights in
    // azimuth); texels between receivers keep U's normal detail (Fig. 7).
    // With sub-sampling U's segments reach below the receiver's tangent plane
    // (see footprintDrop), so that texels of other normals find their light.
    ExactAtReceivers,
    // The exact E at the receivers (as ExactAtReceivers); between them the
    // blockers' mean radiance E / O interpolated and multiplied by each
    // texel's own occlusion O (gi/blocker_radiance.h). No U: the scan keeps
    // the exact moment and the horizon only. Lambert BRDF; others fall back
    // to ExactAtReceivers.
    BlockerRadiance,
};

struct IndirectSettings {
    int bounces = 0;                   // 0: direct light only
    RadiancePyramidSettings radiance;  // k_u = 4, o_u = 2
    bool amortise = false;             // Section 7: alternate direct / indirect on static geometry
    GlossyIndirect glossy = GlossyIndirect::ScalarPyramid;
    LambertIndirect lambert = LambertIndirect::ShKernel;
    // ExactAtReceivers with sub-sampling: U's segments start below the lowest
    // tangent plane of the texels that interpolate the receiver (offsets
    // {-s/2, 0, s/2}^2 cells), lowered by min(footprintDropMax, footprintDrop x
    // (receiver's slope - lowest slope)) (tan, per azimuth; 0 where the
    // footprint is one plane, so a plane stays exactly dark). Measured on 96^2
    // crops at 2x, alps / erosion indirect rel. RMSE: receiver's own plane
    // 18.4 / 23.9 %, footprint 11.7 / 17.2 %, + drop 1 x spread 11.7 / 16.3 %,
    // 8 x 11.5 / 15.2 %, 16 x (at most 1.5) 11.5 / 14.9 %; a constant drop of
    // 1: 11.6 / 14.6 % but light from below a plane receiver's own plane.
    float footprintDrop = 16.0f;
    float footprintDropMax = 1.5f;
    // Azimuths of the indirect scan (0: the visibility's m).
    int azimuths = 0;
};

struct IndirectTimings {
    double pyramid = 0.0, scan = 0.0, shading = 0.0, total = 0.0;
};

/// Per-block scratch of the indirect scan.
struct IndirectScratch {
    std::vector<float> gx, gy, h0, margin;  // rows of the block x padded row
    std::vector<float> footGx, footGy;      // ExactAtReceivers: rows x (lo, hi) x padded row, the footprint's gradient box
    std::vector<float> exact;               // ExactAtReceivers: rows x 3 channels x padded row, E sums
    std::vector<float> lowSlope;            // ExactAtReceivers: padded row, the lowered footprint slope of one azimuth
    std::vector<float> nlp;                 // 3 channels x 4 NLP (+ 3 exact) x padded row, one row and azimuth
    std::vector<float> state;               // the row's running values: 5 + 3 x 5 planes of pad floats
    std::vector<int> groupSteps, active;    // per lane the valid prefix; the groups still walking
};

struct IndirectState {
    RadiancePyramid radiance;
    std::vector<ScanStep> heightSteps;   // azimuths x steps
    std::vector<ScanStep> radianceSteps; // channels x azimuths x steps
    std::vector<int> stepsPerColumn, stepsPerRow;
    std::vector<IndirectScratch> blocks;
    std::array<VisibilityField, 3> u;    // U per channel (16 SH planes at the receivers)
    int uZeroFrom = kShCount;            // U's planes from this one on are known to be 0
    std::array<ShadingLight, 3> lights;
    std::array<ShadeMaps, 2> bounceShade;  // exit radiance of the current / previous bounce
    std::array<Grid, 3> indirect;  // sum of bounces 1..B, full resolution
    std::array<Grid, 3> total;     // direct + indirect
    std::vector<double> bounceMean;  // mean exit radiance (RGB average) of each bounce
    IndirectTimings timings;
    GlossyIndirectState glossy;    // vector-pyramid buffers (GlossyIndirect::VectorPyramid)
    BlockerRadianceState blocker;  // LambertIndirect::BlockerRadiance: horizons, occlusion, receivers' E
    FootprintBox footprint;        // when the caller passes none
};

/// Indirect light of `bounces` bounces over the frame's height pyramid.
/// op: the folded wedge operator of the indirect azimuths (settings.azimuths);
/// direct: bounce 0's exit radiance (full resolution, albedo applied);
/// directShade: the direct shading it came from (its incident SH vectors),
/// needed by GlossyIndirect::VectorPyramid with a non-Lambert BRDF (without
/// it that case throws InputError); footprint: this frame's FootprintBox
/// (ExactAtReceivers with sub-sampling; computed here when null).
void computeIndirect(const HeightPyramid& heights, ConstGridView gradX, ConstGridView gradY,
                     const FoldedWedgeOperator& op, const VisibilityField& envVisibility,
                     const std::array<Grid, 3>& direct, const AlbedoMap* albedo, const ShadingSettings& shading,
                     const IndirectSettings& settings, IndirectState& state, const ShadeMaps* directShade = nullptr,
                     const FootprintBox* footprint = nullptr);

/// Throws InputError when a setting is out of range.
void validateIndirectSettings(const IndirectSettings& s);

/// The scan inputs of receiver row Y (Lambert and glossy scans), pad floats
/// each (0 past the row): the height gradients, the receiver height h0, and
/// the margin 2^-20 |h0| below which a height difference is rounding (a
/// flat plane stays exactly dark).
void loadReceiverRow(const HeightPyramid& pyr, ConstGridView gradX, ConstGridView gradY, int Y, int pad, float* gx, float* gy,
                     float* h0, float* margin);

/// Adds bounce b's exit radiance to st.indirect and records its mean
/// (st.bounceMean[b - 1], RGB average).
void accumulateBounce(const std::array<Grid, 3>& exit, int b, IndirectState& st);

/// st.total = direct + st.indirect.
void sumDirectAndIndirect(const std::array<Grid, 3>& direct, IndirectState& st);

/// The shading lights of U: channel c lights channel c only (identity
/// product matrices over st.u).
void setUShadingLights(IndirectState& st);

/// The step tables of an indirect scan, per azimuth phi[j] (in parallel):
/// heightSteps[j * steps + i] and each receiver's valid prefix (steps inside
/// the domain: stepsPerColumn, azimuths x pad; stepsPerRow, azimuths x nyr);
/// radiance(i, cos, sin, j * steps + i, prefix) records the radiance steps of
/// step i (Lambert: 3 channels; glossy: the SH planes) and narrows the prefix.
using RadianceStepFn = std::function<void(int, double, double, std::size_t, ValidPrefix&)>;
void buildIndirectStepTable(const HeightPyramid& pyr, const std::vector<double>& phi, int pad, std::vector<ScanStep>& heightSteps,
                            std::vector<int>& stepsPerColumn, std::vector<int>& stepsPerRow, const RadianceStepFn& radiance);

}  // namespace terrain::gi

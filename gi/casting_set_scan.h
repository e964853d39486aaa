#pragma once
// The casting-set scan of one receiver row and azimuth over an RGB radiance
// pyramid (Sections 4-5; Eqs. 8, 10, 12, 17): the kernel of the Lambert
// strategies (gi/indirect_sh_kernel.h, gi/indirect_blocker_radiance.h).
//
// For every receiver and azimuth phi_j the scan walks the height pyramid's
// exponential steps (Eq. 14) and keeps the casting set (Eq. 17): the steps
// whose blocking slope beats every earlier one. Each member t_i carries the
// previous bounce's exit radiance u(t_i), read from the radiance pyramid
// (gi/radiance_pyramid.h) at the same step position. Radiance is piecewise
// constant in elevation (Eq. 8): u(t_i) over [omega(t_(i-1)), omega(t_i)),
// with omega(t_(-1)) = omega_min, the tangent plane's elevation along the
// azimuth (Section 3). Every segment is clamped to [omega_min, pi/2] (below
// the tangent plane nothing reaches the receiver). What the kernel sums over
// the segments (CastingMoments):
//
// Nlp (the paper): the segment's NLP projection u(t_i) (vbar(c_i) -
// vbar(c_(i-1))), c the clamped angles; summed, this is Eq. 12. Since vbar is
// a polynomial in s = sin(omega) (Eq. 10's closed form), the kernel
// accumulates u * Delta(s^p), p = 1..4, and converts to the 4 NLP
// coefficients once per receiver and azimuth:
//   u_0 = k0 A1, u_1 = k1 A2, u_2 = k2 (A3 - A1), u_3 = k3 (5 A4 - 6 A2).
//
// GlossyNlp: Nlp with a radiance that depends on the direction (Section
// 5.3, "non-diffuse surfaces", Fig. 5 middle): the member at slope t_i in
// azimuth phi sends u(t_i) = Ebar(t_i) . Y(-d_i) back to the receiver, Ebar
// the exit-radiance SH vector (RGB x 16 planes, gi/glossy_exit_radiance.h)
// read from its pyramid at the step, d_i = (cos phi c, sin phi c, s) with
// c = 1 / sqrt(1 + t_i^2), s = t_i c (16 bilinear reads per channel instead
// of 1); with GlossyPositivity::Clamp no member sends negative radiance,
// u = max(0, .).
//
// Irradiance: the exact clamped-cosine irradiance at the receiver's own
// normal up to dphi / |n|: u(t_i) Delta F with F = f2 - g f1 at the clamped
// segment ends (f1 = (w + sin w cos w) / 2, f2 = sin^2 w / 2, g the tangent
// slope along the azimuth; n = (-gx, -gy, 1), so d . n_h = -g).
//
// Occlusion by distance (Irradiance, AzimuthSteps::distanceGroups): each
// segment's measure |Delta F| is also summed per distance group of its step
// (gi/pyramid.h, distanceGroup), over the azimuths the caller walks: the part
// of the receiver's occlusion each group's members cover, by which the
// indirect cache weighs a change of that group's samples (gi/indirect_cache.h).
//
// Speed: the kernel runs over 8 (AVX2) or 4 (SSE2) lanes, bit-identically
// (core/simd.h), over a block of up to kMaxScanRows receiver rows, step by
// step: at each step every row's groups in turn (each step's reads sweep
// neighbouring stretches of its field, which serve the block's rows while
// they are in cache). A group of lanes stops walking once the
// field's highest height, seen from each lane's receiver at the current
// distance, can no longer beat that lane's running maximum (no member can
// follow; results unchanged).
#include <cstdint>
#include <span>
#include <vector>

#include "gi/pyramid.h"
#include "gi/receiver_tiles.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// What the kernel sums over a receiver's casting-set segments (see above).
enum class CastingMoments {
    Nlp,         // 3 channels x 4 NLP coefficients (LambertIndirect::ShKernel)
    Irradiance,  // 3 channels x the exact clamped-cosine irradiance (LambertIndirect::BlockerRadiance)
    GlossyNlp,   // Nlp from the exit-radiance SH pyramid (GlossyIndirect::VectorPyramid)
};

/// Receiver rows the kernel walks together, at most.
inline constexpr int kMaxScanRows = 8;
/// Moments per segment and channel (Nlp, GlossyNlp).
inline constexpr int kCastingMoments = 4;

/// Per-block scratch of the scan (one per fixed block of receiver rows).
struct IndirectScratch {
    static constexpr int kResultPlanes = 3 * kCastingMoments;     // per row
    static constexpr int kStatePlanes = 4 + 3 * kCastingMoments;  // per row
    int pad = 0;                                                  // floats per padded row
    std::vector<float> gx, gy, h0, margin;  // the block's receiver rows (loadReceiverRow): rows x padded row
    std::vector<float> irradiance;  // BlockerRadiance: rows x 3 channels x padded row, E summed over the azimuths
    // The kernel's output for one azimuth, row r's channel c value k at
    // resultOf(r)[(c * n + k) * pad + X]: n = 4 NLP coefficients (Nlp) or 1 (Irradiance).
    std::vector<float> result;
    // Each row's running values: kStatePlanes planes of pad floats; plane 0 is
    // each receiver's running maximum slope (after the walk: its horizon).
    // Irradiance with distance groups: planes kGroupPlane.. hold each group's
    // summed |Delta F|, added to over every azimuth walked (the caller zeroes them).
    std::vector<float> state;
    static constexpr int kGroupPlane = 4 + 3;
    static_assert(kGroupPlane + kDistanceGroups <= kStatePlanes, "the Irradiance state has room for the groups");
    float* groupOccludersOf(int r) { return stateOf(r) + static_cast<std::size_t>(kGroupPlane) * pad; }
    std::vector<int> groupSteps, active;  // per row: per lane the valid prefix; the groups still walking
    float* resultOf(int r) { return result.data() + static_cast<std::size_t>(r) * kResultPlanes * pad; }
    float* stateOf(int r) { return state.data() + static_cast<std::size_t>(r) * kStatePlanes * pad; }
};

/// Sizes a block's scratch for rows receiver rows of pad floats.
void sizeIndirectScratch(IndirectScratch& sc, int rows, int pad, bool irradiance);

/// One azimuth's step tables as the kernel reads them.
struct AzimuthSteps {
    const ScanStep* heights;      // the height steps
    const ScanStep* radiance[3];  // each channel's radiance steps (not with GlossyNlp)
    const int* stepsPerColumn;    // valid prefix per receiver column (padded row)
    float cosPhi, sinPhi;
    // GlossyNlp: the exit-radiance pyramid's steps (offsets and weights, the
    // same in its 48 planes), each step's 48 plane origins (field + offA,
    // plane c * 16 + k), and whether members send max(0, u)
    const ScanStep* glossy = nullptr;
    const std::uint16_t* const* glossyFields = nullptr;  // bfloat16 (gi/radiance_pyramid.h)
    bool clampNegative = false;
    // Irradiance: each step's distance group, whose |Delta F| the kernel sums
    // (IndirectScratch::groupOccludersOf); null: none summed
    const std::uint8_t* distanceGroups = nullptr;
};

/// One receiver row: padded inputs (loadReceiverRow), the row's valid
/// prefix, and the receivers to scan: column spans (gi/receiver_tiles.h)
/// starting on multiples of 16, each run to its end rounded up to the lane
/// group (indirectRowPad); a whole row: one span [0, nxr). Each receiver's
/// result does not depend on the spans.
struct ReceiverRow {
    int Y, steps;
    std::span<const ColumnSpan> spans;
    const float *h0, *margin, *gx, *gy;
    float hMax;  // the field's highest height: no sample rises above it
};

/// Scans the spans of up to kMaxScanRows receiver rows along one azimuth;
/// out, at the spans' receivers of row r (the r-th of `rows`):
/// IndirectScratch::resultOf(r) (and the running values in stateOf(r)). The
/// scratch is sized for them with the rows' padded length (a multiple of 8,
/// indirectRowPad). The AVX2 and SSE2 variants give identical bits, and each
/// row's the same as scanning it alone.
using CastRowsFn = void (*)(const AzimuthSteps&, std::span<const ReceiverRow> rows, IndirectScratch&);
CastRowsFn castRowsFor(CastingMoments moments);

}  // namespace terrain::gi

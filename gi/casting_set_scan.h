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
// Speed: the kernel runs over 8 (AVX2) or 4 (SSE2) lanes, bit-identically
// (core/simd.h), one receiver row at a time, step by step (each step's reads
// sweep one stretch of its field). A group of lanes stops walking once the
// field's highest height, seen from each lane's receiver at the current
// distance, can no longer beat that lane's running maximum (no member can
// follow; results unchanged).
#include <span>
#include <vector>

#include "gi/receiver_tiles.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// What the kernel sums over a receiver's casting-set segments (see above).
enum class CastingMoments {
    Nlp,         // 3 channels x 4 NLP coefficients (LambertIndirect::ShKernel)
    Irradiance,  // 3 channels x the exact clamped-cosine irradiance (LambertIndirect::BlockerRadiance)
    GlossyNlp,   // Nlp from the exit-radiance SH pyramid (GlossyIndirect::VectorPyramid)
};

/// Per-block scratch of the Lambert scan (one per fixed block of receiver rows).
struct IndirectScratch {
    std::vector<float> gx, gy, h0, margin;  // the block's receiver rows (loadReceiverRow): rows x padded row
    std::vector<float> irradiance;  // BlockerRadiance: rows x 3 channels x padded row, E summed over the azimuths
    // The kernel's output for one row and azimuth, channel c's value k at
    // result[(c * n + k) * pad + X]: n = 4 NLP coefficients (Nlp) or 1 (Irradiance).
    std::vector<float> result;
    // The row's running values: 4 + 3 x 4 planes of pad floats; plane 0 is
    // each receiver's running maximum slope (after the walk: its horizon).
    std::vector<float> state;
    std::vector<int> groupSteps, active;  // per lane the valid prefix; the groups still walking
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
    const float* const* glossyFields = nullptr;
    bool clampNegative = false;
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

/// Scans one receiver row's spans along one azimuth; out, at the spans'
/// receivers: IndirectScratch::result (and the running values in ::state).
/// The AVX2 and SSE2 variants give identical bits. pad: the padded row
/// length, a multiple of 8 (indirectRowPad).
using CastRowFn = void (*)(const AzimuthSteps&, const ReceiverRow&, IndirectScratch&, int pad);
CastRowFn castRowFor(CastingMoments moments);

}  // namespace terrain::gi

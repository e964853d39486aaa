#pragma once
// Per-receiver visibility (Sections 3, 5.2, 6; Eqs. 4, 11, 14-16, 20-21).
//
// For every receiver and every azimuth phi_j the scan walks the exponential
// steps of the height pyramid (Eq. 14) and records the blocking slope
// tan(omega_i) = (f_l(p + tau_i d) - f(p)) / tau_i of each step (Eq. 15, as a
// slope: atan is monotonic, GUIDE 3). The maximum blocking angle (Eq. 16) is
// the maximum of the cubic interpolant through these samples, evaluated at the
// knots and midpoints (or, optionally, the plain maximum of the samples).
//
// omega_min comes from the receiver's normal: the tangent plane cuts the
// vertical plane of azimuth phi at elevation atan(g), g the directional
// derivative of the height (Section 3; below it the cosine is negative, so
// nothing there can light the receiver). sigma = max(omega_max, omega_min)
// gives the NLP visibility vector v = v^-(pi/2) - v^-(sigma) (Eq. 11) and the
// folded wedge operator turns the m vectors into the SH visibility V (Eqs.
// 20-21). Directions below z = 0 are kept: on slopes omega_min < 0.
//
// Design for part 2 (indirect light): the scan keeps, per receiver row and
// azimuth, the whole slope sequence over the steps (VisibilityScratch::slopes)
// before reducing it. The casting set of Eq. 17 is the set of steps whose slope
// exceeds every earlier one; an indirect pass can walk that same sequence and
// accumulate Eq. 12 over it (reading a radiance pyramid at the same step
// positions) without a second scan. maxSlope (per azimuth, per receiver) is
// kept for the same reason.
//
// Schedule: receiver rows are split into a fixed number of blocks; each block
// owns a scratch buffer and runs its rows serially; blocks run in parallel.
// Every receiver is written by exactly one block (gather only), so the result
// is bit-identical for any thread count.
#include <vector>

#include "gi/pyramid.h"
#include "gi/wedge.h"
#include "sim/grid.h"

namespace terrain::gi {

enum class BlockingMax {
    BsplineKnotsAndMidpoints,  // Eq. 16 (paper): cubic interpolant at knots and midpoints
    Samples,                   // plain maximum over the step samples
};

struct VisibilitySettings {
    int azimuths = 32;                                    // m (paper: 32)
    AzimuthInterp interp = AzimuthInterp::Linear;         // M_lin (paper's main operator)
    BlockingMax blockingMax = BlockingMax::BsplineKnotsAndMidpoints;
};

/// Per-block scratch of the scan (one per fixed row block).
struct VisibilityScratch {
    std::vector<float> slopes;  // steps x nxr: slope sequence of the current row and azimuth
    std::vector<float> gradX;   // nxr: dh/dx at the receivers of the current row
    std::vector<float> gradY;
    std::vector<float> h0;      // nxr: receiver heights of the current row
    std::vector<float> nlp;     // 4 x nxr: NLP visibility vectors of the current row and azimuth
};

/// Azimuth set and elevation window of one visibility computation.
struct VisibilityTarget {
    const FoldedWedgeOperator* op = nullptr;  // azimuths + folded wedge operator
    bool window = false;       // key light: restrict to [sinLow, sinHigh] (Section 6)
    float sinLow = -1.0f, sinHigh = 1.0f;
};

/// SH visibility of every receiver (16 planes) and its scan by-products.
struct VisibilityField {
    int nxr = 0, nyr = 0;
    std::vector<float> sh;        // 16 planes of nxr * nyr: V (Eq. 21)
    std::vector<float> maxSlope;  // azimuths planes of nxr * nyr: tan(omega_max) (Eq. 16)
    float* plane(int i) { return sh.data() + static_cast<std::size_t>(i) * nxr * nyr; }
    const float* plane(int i) const { return sh.data() + static_cast<std::size_t>(i) * nxr * nyr; }
};

/// Reusable buffers of the visibility stage.
struct VisibilityState {
    std::vector<VisibilityScratch> blocks;
};

/// Lowest slope used for "nothing blocks in this direction".
inline constexpr float kNoBlocker = -1.0e6f;

/// Computes V for every receiver of the pyramid. gradX/gradY are full
/// resolution height derivatives (metres per metre).
void computeVisibility(const HeightPyramid& pyramid, ConstGridView gradX, ConstGridView gradY,
                       const VisibilitySettings& settings, const VisibilityTarget& target, VisibilityState& state,
                       VisibilityField& out);

/// The m azimuths' maximum blocking slopes of one receiver, computed by the
/// same row kernel (for tests and the casting-set work of part 2).
float maxBlockingSlopeOfSequence(const float* slopes, int count, int stride, BlockingMax rule);

}  // namespace terrain::gi

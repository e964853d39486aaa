#pragma once
// Per-receiver visibility (Nowrouzezahrai & Snyder 2009, Sections 3, 5.2, 6;
// Eqs. 4, 11, 14-16, 20-21).
//
// For every receiver and every azimuth phi_j the scan walks the exponential
// steps of the height pyramid (Eq. 14) and records the blocking slope
// tan(omega_i) = (f_l(p + tau_i d) - f(p)) / tau_i of each step (Eq. 15, as a
// slope: atan is monotonic). Each sample is moved along the ray to the
// nearest crossing of the field's grid lines across the ray's major axis (at
// most half a texel along that axis), where the bilinear field is linear
// between two texels, as in the reference march; tau_i is the moved distance.
// The maximum blocking angle (Eq. 16) is the maximum of the cubic interpolant
// through these samples, evaluated at the knots and midpoints (or, optionally,
// the plain maximum of the samples).
//
// omega_min comes from the receiver's normal: the tangent plane cuts the
// vertical plane of azimuth phi at elevation atan(g), g the directional
// derivative of the height (Section 3; below it the cosine is negative, so
// nothing there can light the receiver). sigma = max(omega_max, omega_min)
// gives the NLP visibility vector v = v^-(pi/2) - v^-(sigma) (Eq. 11) and the
// folded wedge operator turns the m vectors into the SH visibility V (Eqs.
// 20-21). Directions below z = 0 are kept: on slopes omega_min < 0.
//
// Design: the scan is one row kernel templated on a per-step visitor
// (gi/visibility.cpp, scanLanes): for 16 receivers at a time (8 for Eq. 16)
// it walks the steps of one azimuth and hands the visitor the slope
// sequence, step by step, with the steps each receiver's ray still has inside
// the domain. The maximum rules (samples, Eq. 16) are two such visitors. The
// indirect scan (gi/indirect.h: the casting set of Eq. 17 and the Eq. 12
// accumulation over it) walks the same steps with its own kernel
// (scanStepInfo, ValidPrefix). maxSlope (per azimuth, per receiver) is kept so
// that the scan can be checked against its scalar twin (scanReceiverScalar).
//
// Sequence semantics: a receiver's sequence is its valid prefix, the steps
// whose sample lies inside the domain (the ray leaves a convex domain once
// and for all; past that nothing can block). The B-spline maximum (Eq. 16)
// uses the knots and the midpoints between consecutive valid samples, with
// the end sample replicated as its outer neighbour.
//
// Schedule: per frame a table of steps (integer offsets into the phase-split
// raw heights or the level, two linear weights, 1 / tau) is built once per
// (azimuth, step), with the number of valid steps per receiver column and
// row. Receiver rows are split into a fixed number of blocks; each block owns
// a scratch buffer and runs its rows serially; blocks run in parallel. Within
// a row, azimuths two at a time: for each, groups of 16 receivers (8 for
// Eq. 16) run all their steps with 4- or 8-wide SIMD (F4 or F8, core/simd.h;
// each receiver's arithmetic is exactly the scalar one), then the NLP vectors
// of both azimuths and the folded wedge operator update the 16 SH planes of
// the row.
// Every receiver is written by exactly one block (gather only), so the result
// is bit-identical for any thread count.
//
// Receiver tiles (gi/receiver_tiles.h, change-driven GI): given dirty tiles,
// only their receivers are recomputed; rows without a dirty tile are
// skipped, and within a row the kernels run over the dirty column spans
// only, which start on the 16-receiver groups of the full row, so each
// recomputed receiver gets the same bits as in a full computation. The step
// tables stay whole (every column's valid prefix).
#include <vector>

#include "core/grid.h"
#include "gi/pyramid.h"
#include "gi/receiver_tiles.h"
#include "gi/wedge.h"

namespace terrain::gi {

enum class BlockingMax {
    BsplineKnotsAndMidpoints,  // Eq. 16 (paper): cubic interpolant at knots and midpoints
    Samples,                   // plain maximum over the step samples
};

// Defaults: the engine's (gi/settings.h). 16 azimuths instead of the
// paper's 32: with the engine's pyramid the ambient error does not change
// (the order-4 SH truncation of V is the floor) at about 0.7x the frame time
// (bench/results/gi_convergence.md); the plain sample maximum instead of
// Eq. 16's B-spline, which smooths the blocking-angle sequence and does not
// converge to the exact horizon.
struct VisibilitySettings {
    int azimuths = 16;                               // m (paper: 32)
    AzimuthInterp interp = AzimuthInterp::Linear;    // M_lin (paper's main operator)
    BlockingMax blockingMax = BlockingMax::Samples;  // paper: BsplineKnotsAndMidpoints
    // Sub-sampling: omega_min from the lowest tangent plane of the box of
    // gradients of the texels that interpolate the receiver's V (offsets
    // {-s/2, 0, s/2}^2 cells, FootprintBox; gi/frame passes it in the
    // VisibilityTarget) instead of the receiver's own (paper). V is shaded at every texel's own
    // normal (Fig. 7); sky between the receiver's plane and a neighbour's
    // lower one is visible to that neighbour. Its effect on accuracy:
    // README.md, "Footprint tangent planes"; at 1x it changes nothing.
    bool footprintTangent = true;  // paper: false
    bool operator==(const VisibilitySettings&) const = default;
};

/// Per-block scratch of the scan (one per fixed row block), rows padded to a
/// multiple of the kernel's 16 receivers.
struct VisibilityScratch {
    std::vector<float> maxRow;  // nxr: maximum blocking slope of the current row and azimuth
    std::vector<float> gradX;   // 3 x nxr: dh/dx at the receivers of the current row, footprint box lo, hi
    std::vector<float> gradY;
    std::vector<float> h0;             // nxr: receiver heights of the current row
    std::vector<float> nlp;            // 2 x 4 x nxr: NLP visibility vectors of the current row, two azimuths
    std::vector<const float*> rowPtr;  // 2 x steps: each step's two taps for receiver 0 of the current row
};

/// One step of one azimuth, as the scan kernel reads it: the sample of
/// receiver (X, Y) lies on a grid line of the field, between
/// field[Y rowStep + offA + X] and field[Y rowStep + offB + X] (the next row or
/// the next column); the slope is (wA a + wB b - h0) / tau. The raw steps
/// address the phase-split planes, the level steps the level.
struct ScanStep {
    // wA, wB (linear weights) and 1 / (tau * cellSize) of the moved sample,
    // each repeated 4 times so the kernel reads them as aligned vectors
    alignas(16) float w[3][4] = {};
    const float* field = nullptr;
    std::ptrdiff_t rowStep = 0, offA = 0, offB = 0;
};

/// The height a step samples for the receiver at `index` = Y rowStep + X (the
/// scalar form of the scan kernels' lanes; every reader of a step's sample
/// computes it so, to the bit).
inline float stepSample(const ScanStep& st, std::ptrdiff_t index) {
    return st.w[0][0] * st.field[index + st.offA] + st.w[1][0] * st.field[index + st.offB];
}

/// The box [lo, hi] of the height gradients over each receiver's shading
/// footprint: the texels at offsets {-s/2, 0, s/2}^2 cells (clamped to the
/// field), which interpolate the receiver's SH vectors (Fig. 7). Along an
/// azimuth (c, sn) the box's lowest tangent slope, (c >= 0 ? loX : hiX) c +
/// (sn >= 0 ? loY : hiY) sn, bounds the footprint texels' slopes from below.
/// Receiver-grid planes (nxr * nyr each), computed once per frame.
struct FootprintBox {
    int nxr = 0, nyr = 0, subsample = 0;
    std::vector<float> loX, hiX, loY, hiY;
};
/// With `changedGradients` (a box of this grid already there, of gradients
/// that differ only in those rows), only the receivers whose footprint
/// reads a changed row.
void computeFootprintBox(ConstGridView gradX, ConstGridView gradY, int subsample, FootprintBox& out,
                         RowSpan changedGradients = {});

/// Azimuth set and elevation window of one visibility computation.
struct VisibilityTarget {
    const FoldedWedgeOperator* op = nullptr;  // azimuths + folded wedge operator
    bool window = false;                      // key light: restrict to [sinLow, sinHigh] (Section 6)
    // Sub-sampling: omega_min from the footprint box's lowest tangent plane
    // instead of the receiver's own (VisibilitySettings::footprintTangent;
    // null: the receiver's plane).
    const FootprintBox* footprint = nullptr;
    float sinLow = -1.0f, sinHigh = 1.0f;
};

/// SH visibility of every receiver (16 planes, V_00 alone for an operator
/// of one row, none for horizonsOnly) and its scan by-products.
struct VisibilityField {
    int nxr = 0, nyr = 0;
    int planes = kShCount;        // SH planes held (FoldedWedgeOperator::shRows)
    std::vector<float> sh;        // `planes` planes of nxr * nyr: V (Eq. 21)
    std::vector<float> maxSlope;  // azimuths planes of nxr * nyr: tan(omega_max) (Eq. 16)
    float* plane(int i) { return sh.data() + static_cast<std::size_t>(i) * nxr * nyr; }
    const float* plane(int i) const { return sh.data() + static_cast<std::size_t>(i) * nxr * nyr; }
};

/// What a scan's step tables are a function of: the azimuths and the
/// pyramid's layout (its step distances and levels, its grids, where its
/// fields lie in memory and their strides), not the heights the fields hold.
struct StepTableKey {
    std::vector<double> phi;
    int nxrPad = 0, nx = 0, ny = 0, nxr = 0, nyr = 0, subsample = 0;
    float cellSize = 0.0f;
    const float* raw = nullptr;  // the raw phases
    std::ptrdiff_t rawWidth = 0, rawPlane = 0;
    std::vector<double> tauCells;
    std::vector<int> stepLevels;
    std::vector<const float*> levelData;  // each level's first texel
    std::vector<std::ptrdiff_t> levelStrides;
    bool operator==(const StepTableKey&) const = default;
};

/// The key of a scan over `pyr` along the azimuths `phi` (radians) with
/// receiver rows padded to nxrPad.
StepTableKey stepTableKey(const HeightPyramid& pyr, const std::vector<double>& phi, int nxrPad);

/// One scan's step tables (computeVisibility).
struct StepTables {
    StepTableKey key;
    std::vector<ScanStep> steps;      // azimuths x steps
    std::vector<int> validColumns;    // azimuths x steps: receivers X in [first, last] sample inside (x)
    std::vector<int> validRows;       // azimuths x steps: same for receiver rows Y (pairs)
    std::vector<int> stepsPerColumn;  // azimuths x padded nxr: valid-prefix length from x alone
    std::vector<int> stepsPerRow;     // azimuths x nyr: valid-prefix length from y alone
    std::vector<float> cosSin;        // azimuths x 2: cos, sin of each azimuth (float)
};

/// Reusable buffers of the visibility stage.
struct VisibilityState {
    std::vector<VisibilityScratch> blocks;
    // the tables of the last scans (the environment's and each key light's,
    // which take turns), the running scan's first: a scan whose key one of
    // them holds reuses it
    static constexpr std::size_t kKeptTables = 4;
    std::vector<StepTables> tables;
    DirtySpans spans;             // the receiver columns to compute, per row
    std::vector<int> busyBlocks;  // the row blocks with a row to compute
};

/// One step of the scan table as computeVisibility builds it (exposed for
/// gi/indirect, which walks the same steps over a radiance pyramid): step i of
/// azimuth (cosPhi, sinPhi) read from `pyramid` (raw heights or a level), and
/// the receivers X in [xFirst, xLast], Y in [yFirst, yLast] whose sample lies
/// inside the domain. Receiver (X, Y) reads the field's texels (k X + tapX,
/// k Y + tapY) and (k X + tapX + nextX, k Y + tapY + nextY), k the receiver
/// spacing in the field's texels (the sub-sampling s for raw heights, in
/// cells; 1 for a level, on the receiver grid) and (nextX, nextY) one texel
/// across the ray's major axis: (0, 1) or (1, 0).
struct ScanStepInfo {
    ScanStep step;
    int xFirst = 0, xLast = -1, yFirst = 0, yLast = -1;
    int tapX = 0, tapY = 0, nextX = 0, nextY = 0;
};
ScanStepInfo scanStepInfo(const HeightPyramid& pyramid, int i, double cosPhi, double sinPhi);
/// The same for a step of one's own: a raw step (level -1) at any distance,
/// or one of the pyramid's level steps.
ScanStepInfo scanStepInfoAt(const HeightPyramid& pyramid, const PyramidStep& step, double cosPhi, double sinPhi);

/// Valid prefixes of one azimuth's step table when several fields are read
/// at each step (gi/indirect: heights and radiance): a receiver's sequence
/// is its prefix of steps whose samples lie inside the domain in every field
/// (the ray leaves a convex domain once and for all). Per step: narrow() with
/// each field's ScanStepInfo, then commit(i); colSteps (pad) and rowSteps
/// (nyr) then hold each receiver column's / row's prefix length.
class ValidPrefix {
public:
    ValidPrefix(int nxr, int nyr, int pad, int* colSteps, int* rowSteps);
    void narrow(const ScanStepInfo& s);
    void commit(int step);
    /// The receivers inside the domain at every step narrowed so far, columns
    /// [x0, x1] and rows [y0, y1] (empty where first > last).
    struct Receivers {
        int x0, x1, y0, y1;
    };
    Receivers receivers() const { return {xLo_, xHi_, yLo_, yHi_}; }

private:
    int xLo_, xHi_, yLo_, yHi_;
    int *col_, *row_;
};

/// Lowest slope used for "nothing blocks in this direction".
inline constexpr float kNoBlocker = -1.0e6f;
/// Indirect scans: a height difference below kHeightMarginRel |h0| is float
/// rounding, not a blocker (a flat plane gets exactly no indirect light).
inline constexpr float kHeightMarginRel = 1.0f / 1048576.0f;  // 2^-20

/// Computes V for every receiver of the pyramid. gradX/gradY are full
/// resolution height derivatives (metres per metre).
/// With `only` (receiver tiles of this receiver grid), out must already hold
/// a result of the same target and settings (only its sizes are checked:
/// InputError when they are not this grid's and azimuth count's): the
/// receivers of the dirty tiles are recomputed (V and maxSlope),
/// bit-identical to a full computation, and every other receiver keeps its
/// values. Null: every receiver.
void computeVisibility(const HeightPyramid& pyramid, ConstGridView gradX, ConstGridView gradY,
                       const VisibilitySettings& settings, const VisibilityTarget& target, VisibilityState& state,
                       VisibilityField& out, const ReceiverTiles* only = nullptr);

/// Eq. 16 over one receiver's valid slope sequence (scalar twin of the scan's
/// visitors; scanReceiverScalar uses it).
float maxBlockingSlopeOfSequence(const float* slopes, int count, BlockingMax rule);

/// Scalar twin of the scan for one receiver and azimuth phi: walks the same
/// steps (same weights and arithmetic) with its own bounds test and returns
/// the maximum blocking slope, bit-identical to VisibilityField::maxSlope.
float scanReceiverScalar(const HeightPyramid& pyramid, int X, int Y, double phi, BlockingMax rule);

}  // namespace terrain::gi

#pragma once
// Conservative bounds on how much the environment visibility and the ambient
// light of a receiver can change when the heights change, for change-driven
// GI on animated terrain: a tile of receivers may keep its cached results
// when the bound says they cannot have moved by more than a tolerance.
//
// The chain, each link derived from the code it bounds:
//   |dh| per cell -> MaxChangePyramid (block maxima, box queries)
//   -> each pyramid sample's reach (stepReachCells: which cells a sample of
//      step i reads, through the bilinear taps, the level blend, the B-spline
//      synthesis and the box / max decimations of gi/pyramid.cpp)
//   -> every blocking slope (h(t_i) - h0) / t_i of the scan (gi/visibility.h)
//      per tile (boundSlopeChange) or per tile and azimuth, weighed by the
//      filters (boundSlopeChangePerAzimuth), and the height gradients of the
//      tangent planes and normals (boundGradientChange)
//   -> the ambient map (ambientChangeBound, ambientChangeBoundPerAzimuth).
// The bounds hold in real arithmetic. The float results carry their own
// rounding on top (a few dozen ulp of the heights over the step length for a
// slope); a caller's tolerance is far above it. Where no height within a
// result's reach changed, the result is recomputed from the same floats by
// the same operations, so a zero bound means bit-identical results.
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "core/grid.h"
#include "core/simd.h"
#include "gi/pyramid.h"
#include "gi/receiver_tiles.h"
#include "gi/visibility.h"

namespace terrain::gi {

/// Block maxima of the absolute height change: level k holds the maximum of
/// |dh| over 2^k x 2^k cells (blocks aligned to multiples of 2^k, the last
/// ones cut by the grid's edge); level 0 is |dh| itself, the last level 1 x 1.
/// `sums` holds the sums of |dh| over the same blocks (sums[0] is empty:
/// level 0 is its own sum; each sum rounded up to the next float), unless
/// withSums is false.
/// `changed` is a box of cells (inclusive; empty when x0 > x1) that holds
/// every cell with |dh| > 0, from a coarse level's blocks: queries of boxes
/// outside it answer 0 at once, as they would after their walk.
struct MaxChangePyramid {
    int nx = 0, ny = 0;
    std::vector<Grid> levels;
    std::vector<Grid> sums;
    bool withSums = true;  // false: `sums` are not built (the owner never asks sumChangeInBox)
    struct {
        int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
    } changed;
};

/// p.changed as a half-open box of cells (CellBox::none() when nothing changed).
inline CellBox changedCells(const MaxChangePyramid& p) {
    const auto& c = p.changed;
    return c.x0 > c.x1 ? CellBox::none() : CellBox{c.x0, c.y0, c.x1 + 1, c.y1 + 1};
}

/// The smallest float not below the real |b - a| (a, b finite), in float
/// arithmetic, per lane (V = float or a simd lane type): the rounded
/// difference s and its rounding error e (Knuth's TwoSum, exact in
/// round-to-nearest), then s's magnitude one float up when e pointed away
/// from zero. (The double difference is exact only for exponents less than
/// 30 apart.)
template <class V>
[[gnu::always_inline]] inline V absDifferenceUp(V a, V b) {
    const V s = b - a;
    const V bPart = s + a, aPart = s - bPart;  // TwoSum(b, -a)
    const V e = (b - bPart) - (a + aPart);
    if constexpr (std::is_same_v<V, float>) {
        const bool up = s >= 0.0f ? e > 0.0f : e < 0.0f;
        return std::bit_cast<float>(std::bit_cast<std::uint32_t>(std::fabs(s)) + (up ? 1u : 0u));
    } else {
        using I = typename simd::LaneTraits<V>::I;
        const V zero = simd::splat<V>(0.0f);
        const I up = s >= zero ? e > zero : e < zero;  // -1 where rounding up
        return std::bit_cast<V>((std::bit_cast<I>(s) & 0x7fffffff) - up);
    }
}

/// Builds (or rebuilds, reusing every buffer of the same size) the pyramid
/// of |dh|; the sign of dh does not matter.
void buildMaxChangePyramid(ConstGridView dh, MaxChangePyramid& out);

/// The same for dh = after - before (same sizes), each |dh| rounded up to
/// the next float so that it bounds the real difference of the two floats.
/// `differing` holds every cell where before and after may differ (every
/// cell by default): with a pyramid of this size in `out`, only those cells,
/// those of its changed box and the blocks holding them are redone (the
/// others are 0 either way), the same values as a whole build.
void buildMaxChangePyramid(ConstGridView before, ConstGridView after, MaxChangePyramid& out, CellBox differing = {});

/// The same for the largest change over several fields of one size (the
/// channels of a radiance): max over c of |after[c] - before[c]| per cell,
/// rounded up. Throws InputError when the counts or the sizes differ.
void buildMaxChangePyramid(std::span<const ConstGridView> before, std::span<const ConstGridView> after,
                           MaxChangePyramid& out, CellBox differing = {});

/// max |dh| over the cells [x0, x1] x [y0, y1] (inclusive, clamped to the
/// grid; 0 when the clamped box is empty), exact: from the at most 4 x 4
/// blocks of the finest level that covers the box with so few, it descends
/// into the blocks the box's edges cut, only where they could raise the
/// maximum found so far. With `above`: the larger of it and that maximum,
/// without descending into blocks that cannot exceed it (a caller keeping a
/// running maximum).
float maxChangeInBox(const MaxChangePyramid& p, int x0, int y0, int x1, int y1, float above = 0.0f);

/// An upper bound on maxChangeInBox's answer for the same box, without its
/// descent along the box's edges: the largest of the at most 8 x 8 blocks
/// of the finest level that covers the box with so few (the box rounded
/// out to those blocks: at most 2^k - 1 cells more on each side at level
/// k, less than a third of the box's longer side). For callers that query many
/// boxes per frame, where the exact walk costs more than a few cells
/// more in the bound (gi/radiance_sample_change.cpp).
float maxChangeCoveringBox(const MaxChangePyramid& p, int x0, int y0, int x1, int y1, float above = 0.0f);

/// Upper bound of the sum of |dh| over the same box: the sum over the at
/// most 4 x 4 blocks that cover it (up to a block larger on each side).
/// Throws InputError for a pyramid built without its sums.
double sumChangeInBox(const MaxChangePyramid& p, int x0, int y0, int x1, int y1);

/// max |dh| over the whole grid (the top level).
float maxChangeAll(const MaxChangePyramid& p);

// ---- reach of a pyramid sample ----------------------------------------------------
// Step i of a HeightPyramid samples a field at a point q (full-resolution
// cells). The reach r_i is a Chebyshev radius around q: no height change at
// a cell farther than r_i from q can alter the sample. From gi/pyramid.cpp
// and gi/visibility.cpp (makeStep):
//  - raw steps (level < 0): q lies on a grid line of the full-resolution
//    heights, read linearly between the two texels either side across it,
//    both less than one cell from q (the replicated padding column and row
//    hold the edge texel, which is closer): r = 1.
//  - level steps: q lies on a grid line of the level, blown out to the
//    receiver grid, and is read between two receiver texels less than one
//    receiver spacing s from q. A level texel at receiver (X, Y) blends
//    S_o and S_(o+1) at cell (s X, s Y) with weights 1 - q_l and q_l (q_l = 0
//    reads S_o alone; the last octave is read alone). S_0 is the height at
//    that cell (reach 0). S_o, o >= 1, is the cubic B-spline synthesis of
//    the octave image B_o at u = (x + 0.5) / 2^o - 0.5: taps floor(u) - 1 ..
//    floor(u) + 2, clamped to the image (clamping only moves a tap towards
//    the point), and B_o texel k decimates (mean or max, with the edge
//    replicated inside its own block) exactly the cells [k 2^o, (k + 1) 2^o).
//    The farthest cell of tap floor(u) - 1 lies (u - floor(u) + 1.5) 2^o -
//    0.5 < 2.5 2^o - 0.5 cells before x, that of tap floor(u) + 2 at most
//    (floor(u) + 2.5 - u) 2^o - 0.5 <= 2.5 2^o - 0.5 after it; the same holds
//    along y (the synthesis is separable). So R_o = 2.5 2^o - 0.5 and
//    r = s + R_o, with o the finer octave for q_l = 0 and the coarser one
//    otherwise.

/// r_i of every step of the pyramid, in full-resolution cells.
std::vector<float> stepReachCells(const HeightPyramid& pyr);

/// R_o of level `level` (>= 0): no change at a cell farther than this
/// (Chebyshev, cells) from a level texel's cell can alter the texel.
double levelReachCells(const HeightPyramid& pyr, int level);

/// Factor by which a change of the heights by at most M in the max norm can
/// move any level sample: every filter of the pyramid is 1-Lipschitz in the
/// max norm (the 2 x 2 mean and max, the B-spline weights, which are
/// non-negative for a fraction in [0, 1) and sum to 1, the level blend and
/// the scan's linear read, weights in [0, 1]) except the mean / max blend,
/// whose weights 1 - b and b (b = peakBlend) give |1 - b| + |b|.
float heightFilterLipschitz(const HeightPyramid& pyr);

// ---- blocking slopes per tile ----------------------------------------------------
// Tile (tx, ty) holds receivers X in [T tx, T tx + T), Y in [T ty, T ty + T)
// (cut by the grid), T = tileReceivers; tiles are row-major, tileCount(nxr, T)
// per row. Step i of azimuth (c, sn) samples at the distance t' (cells) the
// scan moves it to: a whole number n >= 1 of field texels (size u: 1 cell for
// raw steps, s for level steps) along the major axis, t' = n u / |major| with
// n = max(1, round(tau_i |major| / u)) and |major| >= 1/sqrt2, so
//   max(u, tau_i - u / sqrt2) <= t' <= max(sqrt2 u, tau_i + u / sqrt2),
// and the slope is (h(q) - h0) / (t' cellSize), h0 the height at the
// receiver's cell. With M_i the largest |dh| within t'_max + r_i of any
// receiver of the tile (the tile's cell box dilated by that Chebyshev
// distance) and M0 the largest |dh| over the tile's cell box (which holds
// the receivers' cells, where h0 is read),
//   |d slope_i| <= (L M_i + M0) / (t'_min cellSize)   (L: heightFilterLipschitz)
// and the bound of the tile is the maximum over the steps. The maximum
// blocking slope (BlockingMax::Samples) is a maximum over a sequence whose
// length depends on geometry only, so it moves by at most the same bound;
// Eq. 16's midpoints (9 (s0 + s1) - (s_-1 + s2)) / 16 move by up to 20 / 16
// of it (blockingMaxLipschitz).

/// Bound on |change| of every blocking slope of tile (tx, ty) (metres per
/// metre). `dh` must cover the pyramid's full-resolution grid.
float boundOfTile(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx, int ty);

/// Per step of the pyramid, what boundOfTile reads for a tile of one
/// receiver: t'_min (cells) and the half-size (cells) of the square around
/// the receiver's cell that holds every cell the step's samples read from it
/// along any azimuth.
struct StepSquare {
    double tauMin = 0.0;
    int halfSize = 0;
};
std::vector<StepSquare> stepSquares(const HeightPyramid& pyr);

/// A float not below the non-negative double v (the bounds are rounded up).
float floatNotBelow(double v);

/// boundOfTile of every tile, row-major (tileCount(nxr, T) x tileCount(nyr, T)),
/// in parallel. Throws InputError when tileReceivers < 1 or the sizes of dh
/// and the pyramid differ.
void boundSlopeChange(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers,
                      std::vector<float>& tileBound);

// ---- blocking slopes per tile and azimuth ------------------------------------------
// A height change moves the slopes of an azimuth only when it lies within
// reach of that azimuth's samples. Step i of azimuth phi samples receiver p at
// q = p + t' (cos phi, sin phi) (gi/visibility.cpp, makeStep: the sample is
// moved along the ray), t' in [t'_min, t'_max] as above; over the tile's
// receivers these points fill the tile's cell box swept along that segment,
// whose bounding box, dilated by r_i plus one cell (the engine's float
// direction differs from the exact one by far less), holds every cell the
// step reads. With M_ij the largest |dh| there the bound of azimuth j is the
// maximum over the steps of (D_ij + M0) / (t'_min cellSize), with D_ij <= L
// M_ij the largest move of a level sample there; it is never larger than the
// tile's bound over all azimuths.
//
// D_ij weighs the change by the filters: a level sample of octave o >= 1 is a
// convex combination (bilinear read, level blend, B-spline taps) of the octave
// images' texels within the box, blended as (1 - b) mean + b max (b =
// peakBlend). A max texel moves by at most M_ij. A mean texel is the 2 x 2
// mean applied o times, the edge replicated: a separable weight w_o(x) w_o(y)
// per cell, 2^-o per axis inside whole blocks and up to 1 in the block the
// grid's edge cuts. Each cell lies in one texel of B_o, and the sample
// weighs that texel by at most 2/3 per axis (the B-spline's largest tap; the
// convex combinations keep it), or 1 on the image's first and last texels,
// where clamped taps coincide. So it moves by at most min(M_ij, W S_ij),
// S_ij the sum of |dh| over the box (sumChangeInBox) and W the largest cell
// weight there times those tap weights (of the finer octave for a blended
// level, whose weights are the larger), and
//   D_ij = |1 - b| min(M_ij, W S_ij) + |b| M_ij.
// A far change of small area then counts by its share of the filter, not by
// its full height. Raw steps and octave 0 read heights: D_ij = M_ij.

/// Bound on |change| of every blocking slope of tile (tx, ty) along azimuth
/// phi (radians, from +x towards +y).
float azimuthBoundOfTile(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx, int ty,
                         double phi);

/// azimuthBoundOfTile of every tile at the m = azimuths samples phi_j = 2 pi
/// j / m of the full circle (gi/wedge.h, foldFullCircle): tileBound[t m + j],
/// tiles row-major as boundSlopeChange (same errors; InputError for azimuths
/// < 1). With `only` (one flag per tile), of the flagged tiles alone: the
/// others' values are 0.
void boundSlopeChangePerAzimuth(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int azimuths,
                                std::vector<float>& tileBound, std::span<const std::uint8_t> only = {});

// A key light's visibility reads only the azimuths of its region of the
// sky, [phi0, phi1]: the sample points of every such azimuth lie in the tile's
// cells swept from t'_min to t'_max along the directions, whose bounding box
// spans t' times the ranges of cos phi and sin phi over [phi0, phi1] (the
// ends, and +-1 where a multiple of pi / 2 lies between); dilated and
// weighed as above, it bounds every blocking slope of those azimuths, and it
// is never larger than the tile's bound over all azimuths.

/// Bound on |change| of every blocking slope of tile (tx, ty) along the
/// azimuths [phi0, phi1] (radians, phi0 <= phi1).
float rangeBoundOfTile(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx, int ty,
                       double phi0, double phi1);

/// rangeBoundOfTile of every tile, row-major as boundSlopeChange (same
/// errors; InputError when phi0 > phi1). With `only` (one flag per tile), of
/// the flagged tiles alone: the others' values are 0.
void boundSlopeChangeOverRange(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, double phi0,
                               double phi1, std::vector<float>& tileBound, std::span<const std::uint8_t> only = {});

/// How much the maximum blocking slope can move per unit of the per-step
/// bound: 1 for the sample maximum, 20 / 16 for Eq. 16's midpoints.
float blockingMaxLipschitz(BlockingMax rule);

// ---- tangent planes and normals per tile -------------------------------------------
// omega_min (gi/visibility.h) reads the height gradient at the receiver, or
// with sub-sampling the box of gradients over its footprint texels (offsets
// {-s/2, 0, s/2}^2 cells, clamped), whose bounds are minima and maxima of
// gradients (1-Lipschitz); shading reads each texel's own gradient. The
// gradient (gi/frame.cpp computeGradient) is (h(x+1) - h(x-1)) / (2
// cellSize) inside, moving by at most M / cellSize, and one-sided (h(1) -
// h(0)) / cellSize on the border rows and columns, moving by at most 2 M /
// cellSize, M the largest |dh| over the footprint dilated by one cell.

/// Bound on |change| of each gradient component (metres per metre) over the
/// footprint texels of tile (tx, ty).
float gradientBoundOfTile(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx, int ty);

/// gradientBoundOfTile with tiles of one receiver for the receivers [X0, X1)
/// of row Y, into out[X] (the same values: the largest |dh| over each
/// receiver's dilated footprint, read from |dh| itself row by row instead
/// of one box query per receiver). `columnMax` is scratch.
void receiverGradientBounds(const MaxChangePyramid& dh, const HeightPyramid& pyr, int Y, int X0, int X1, float* out,
                            std::vector<float>& columnMax);

/// The largest over the receivers of tile (tx, ty) of each one's own
/// gradientBoundOfTile (tiles of one receiver): the tile's own bound where
/// its footprint keeps off the field's edges (the receivers' boxes then
/// make up the tile's), else taken receiver by receiver.
float largestReceiverGradientBound(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers, int tx,
                                   int ty);

/// gradientBoundOfTile of every tile (layout and errors as boundSlopeChange).
void boundGradientChange(const MaxChangePyramid& dh, const HeightPyramid& pyr, int tileReceivers,
                         std::vector<float>& tileBound);

// ---- from slopes to shade ---------------------------------------------------------
// Exact integral: along azimuth phi the sky is visible above the elevation
// sigma(phi) = atan(t(phi)); the occluded band moves by |d sigma| <= |dt|, and
// a band of elevation width d over the full circle has a cosine-weighted
// solid angle of at most 2 pi d (cos <= 1), so irradiance / pi moves by at
// most 2 Lmax max|dt| (kShadePerSlopeExact).
//
// The engine's ambient map is a different function of the horizon. It is
// lam(N) . V / pi (gi/shading.h): V is the order-4 SH projection of W, the
// azimuthal interpolation (non-negative weights summing to 1) of each
// azimuth's order-4 Legendre approximation in z = sin(elevation) of "visible
// above sin(sigma)" (Eq. 11, gi/wedge.h); lam has bands 0..2 only, so the
// ambient is the integral of W times k(N . w), k the band-limited clamped
// cosine / pi. Moving sin(sigma) of azimuth sample j to u changes it by
// integral over phi of beta_j(phi) g(u, phi), with g the order-4 Legendre
// projection in z of k(N . w(z, phi)): g peaks above k's maximum, so the
// per-slope constant is 2 pi max|g| over normals, azimuths and u, rounded up
// (kShadePerSlope; the unit test 'gi.change_bound: SH constants' computes
// max|g| by quadrature and checks the constant against it, and the ambient
// tests check it against the engine's outputs). The maximum of the blocking
// slope and the tangent slope moves by at most the larger of their moves,
// and sin(atan t) is 1-Lipschitz.
//
// A normal moving by |dN| changes k(N . w) - k(N' . w) = (dN . w)(k1 + k2 (N
// + N') . w) for the quadratic k = k0 + k1 t + k2 t^2; k integrates to the
// same value for every normal, so W may be shifted to its mid-range first:
// the change is at most (range W / 2) max over m in [0, 1] (the integrand is
// convex in m: the ends) of the integral of |x| |k1 + 2 k2 m z| over the
// sphere, times |dN| (kShadePerNormal; checked by the same test). |dN| <=
// |d gradient| (the unit normal is a 1-Lipschitz function of the gradient)
// <= sqrt2 G for a per-component bound G, and the tangent slope gx c + gy sn
// moves by at most sqrt2 G too.
//
// Scope: the ambient map (uniform unit sky: Lmax = 1) and the direct light
// of a uniform sky of radiance Lmax at white albedo. A non-uniform sky's SH
// product reshapes the kernel; its bound needs its own constant. Texels
// between receivers interpolate the V of up to four receivers (Fig. 7), so
// their bound is the largest of the tiles those receivers belong to.
//
// Per azimuth: sample j enters W with the weight beta_j(phi) (the hat of
// linear interpolation, or the cubic B-spline of the full circle), whose
// integral over phi is 2 pi / m for m evenly spaced samples. Moving sample
// j's sin(sigma) by du_j changes the ambient by at most (2 pi / m) max|g|
// |du_j|, so the whole change is at most (kShadePerSlope / m) sum_j |du_j|
// (ambientChangeBoundPerAzimuth): an azimuth whose horizon did not move
// costs nothing, where the full-circle form charges every azimuth with the
// largest move. |du_j| <= max(slope bound of azimuth j, sqrt2 G) as above.
inline constexpr float kShadePerSlopeExact = 2.0f;
inline constexpr float kShadePerSlope = 2.25f;
inline constexpr float kShadePerNormal = 1.05f;

/// Bound on |change| of the ambient map (times maxSkyRadiance for a uniform
/// sky) at the receiver texels of a tile, from the tile's slope bound (its
/// maximum blocking slope's: boundOfTile times blockingMaxLipschitz) and its
/// gradient bound; `withNormals` adds the shading normals' move
/// (kShadePerNormal), which a cached V does not see.
float ambientChangeBound(float slopeBound, float gradientBound, float maxSkyRadiance, bool withNormals);

/// The same from per-azimuth slope bounds of the m = azimuths samples of the
/// full circle (each the maximum blocking slope's: azimuthBoundOfTile times
/// blockingMaxLipschitz) and the gradient bound.
float ambientChangeBoundPerAzimuth(const float* slopeBound, int azimuths, float gradientBound, float maxSkyRadiance,
                                   bool withNormals);

// ---- a key light's shade ----------------------------------------------------------
// With the exact cosine (gi/key_light_exact.h) a key light adds rgb f
// max(0, N . l) at white albedo, f in [0, 1] the visible fraction of its
// window [phi0, phi1] x [sinLow, sinHigh] (Section 6): its visibility's band-0
// coefficient over the window's solid angle. Along each of the light's
// azimuths the visible part of the window is sinHigh - clamp(sin sigma,
// sinLow, sinHigh), and the folded operator averages these over the
// azimuths with non-negative weights (gi/wedge.h), so f moves by at most
// max |d sin sigma| / (sinHigh - sinLow) <= max |dt| / (sinHigh - sinLow),
// and by no more than 1. sigma is the larger of the blocking and the
// tangent-plane elevation, so |dt| <= max(slope bound, sqrt2 G) as for the
// ambient. The shading itself reruns at the new normals (only f is cached),
// so the shade moves by at most max(rgb) times that: a small light (a sun of
// 3 degrees at 30 degrees is a window 0.09 high in sin) turns a slope change
// into a shade change ten times larger than the ambient map's.

/// Bound on |change| of one key light's visible fraction f at the receiver
/// texels of a tile (in [0, 1]; times the light's largest channel, a bound
/// on its exact-cosine shade at white albedo), from the tile's slope bound
/// over the light's azimuths (its maximum blocking slope's: rangeBoundOfTile
/// times blockingMaxLipschitz) and its gradient bound. 0 when both bounds are 0.
float keyLightFractionBound(float slopeBound, float gradientBound, float sinLow, float sinHigh);

}  // namespace terrain::gi

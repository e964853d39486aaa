#pragma once
// A diagnosis for `terrain_bench gi-bound-diagnosis`: how much tighter the
// environment V bound of a receiver becomes when it knows the receiver's
// horizon at the anchor, not only how far each of its samples may move.
//
// Along one azimuth a receiver's maximum blocking slope is H = max_i s_i
// over its steps' slopes s_i (BlockingMax::Samples, the engine's rule). If
// each slope moves by at most D_i (gi/receiver_azimuth_bound.h: the |dh|
// pyramid read at the step's taps, plus the receiver's own |dh|, over the
// step's length), then
//     H' <= max_i (s_i + D_i)      and      H' >= s'_k >= H - D_k,
// k the step that holds the horizon. So
//     |H' - H| <= max(D_k, max_i (s_i + D_i) - H)                  (ideal)
// where the plain bound charges max_i D_i: a sample that lies below the
// horizon by more than it can rise moves nothing, and a lowered sample
// moves the horizon only if it is the horizon. The ideal form reads every
// anchor slope (what a scan costs); a cheap one keeps per receiver and
// azimuth only k and the gap g = H - max_(i != k) s_i to the second-highest
// sample:
//     |H' - H| <= max(D_k, max_(i != k) D_i - g)                    (top two)
// V reads sigma = max(H, T) per azimuth, T the tangent slope of the lowest
// tangent plane of the receiver's footprint box (gi/visibility.h), which
// moves by at most dT = (|cos phi| + |sin phi|) G, G the bound on each
// gradient component's change (gi/change_bound.h). The engine charges
// every azimuth with max(dH, sqrt2 G); knowing which of H and T is sigma,
//     |sigma' - sigma| <= max(dH, T + dT - H)    where H >= T,
//                         max(dT, H + dH - T)    where T > H
// (the other term clamped at 0): a tangent plane well below the horizon
// moves nothing (tangent-aware). The new heights' footprint boxes are at
// hand when a frame plans (its gradients come first), so T' itself may
// replace the bound dT: |sigma' - sigma| <= the larger of |max(H + dH, T')
// - sigma| and |max(H - dH, T') - sigma| (exact tangent).
// The exact tangent is also paired with the plain dH = max_i D_i and with
// the visibility tile's per-azimuth slope bound (gi/change_bound.h): forms
// that need the anchor's horizons (which a V keeps, VisibilityField::
// maxSlope) and tangent planes but not its every slope.
// All of them hold in real arithmetic (float rounding is not counted: this
// is a measurement, not a bound the engine relies on).
#include <span>
#include <vector>

#include "bench/elevation_weight.h"
#include "core/grid.h"
#include "gi/change_bound.h"
#include "gi/pyramid.h"
#include "gi/receiver_azimuth_bound.h"

namespace terrain::bench {

/// Per receiver (row-major), the environment V's ambient change bound
/// (gi::ambientChangeBoundPerAzimuth over the azimuths phi) from each
/// variant's per-azimuth bounds: with each receiver's own gradient bound for
/// the first three, whose slope bounds leave the tangent planes out; the
/// others count them already (dT or T').
struct HorizonAwareBounds {
    enum Variant {
        Plain,
        Ideal,
        TopTwo,
        IdealTangent,
        TopTwoTangent,
        IdealExactTangent,
        TopTwoExactTangent,
        PlainExactTangent,
        TileExactTangent,
        IdealExactTangentWeighted,
        TopTwoExactTangentWeighted,
        PlainExactTangentWeighted,
        kVariants
    };
    static constexpr const char* kNames[kVariants] = {
        "samples' own change (max_i D_i, gi/receiver_azimuth_bound.h)",
        "horizon-aware, every anchor slope (ideal)",
        "horizon-aware, the horizon's step and the gap to the second sample (top two)",
        "ideal and tangent-aware",
        "top two and tangent-aware",
        "ideal, exact tangent",
        "top two, exact tangent",
        "samples' own change, exact tangent",
        "the visibility tile's slope bound per azimuth (gi/change_bound.h), exact tangent",
        "ideal, exact tangent, elevation weight (bench/elevation_weight.h, an estimate)",
        "top two, exact tangent, elevation weight (an estimate)",
        "samples' own change, exact tangent, elevation weight (an estimate)",
    };
    std::vector<float> bound[kVariants];
};

/// `anchor`: the pyramid of the heights the cached V was computed from and
/// `box` its footprint boxes (gi::computeFootprintBox of its gradients),
/// `newBox` the new heights' ones;
/// `levels`: the |dh| pyramid (gi::buildChangeLevels) of `dh`, the change
/// from the anchor's heights to the new ones; phi: the V's azimuths;
/// tileSlopeBound: gi::boundSlopeChangePerAzimuth over tiles of `tile`
/// receivers for the same change and azimuths; gradX, gradY: the new
/// heights' gradients (the texels' normals the weighted variant shades at).
HorizonAwareBounds horizonAwareBounds(const gi::HeightPyramid& anchor, const gi::FootprintBox& box,
                                      const gi::FootprintBox& newBox, const gi::ChangeLevels& levels,
                                      const gi::MaxChangePyramid& dh, std::span<const double> phi, float lipschitz,
                                      const std::vector<float>& tileSlopeBound, int tile, ConstGridView gradX,
                                      ConstGridView gradY);

/// Per receiver (row-major), what the conversion makes of the true moves:
/// each azimuth's sigma to sigma' (in slope, tan) from the two frames'
/// maximum blocking slopes (VisibilityField::maxSlope, planes in the order
/// of phi) and footprint boxes, through gi::ambientChangeBoundPerAzimuth
/// (`frames`) and through the elevation weight at the new normals
/// (`weighted`). Where the first is far above the true change of the
/// ambient, the slack is the conversion (one weight for every elevation and
/// normal), not the bound on the slopes.
struct TrueSigmaBounds {
    std::vector<float> frames, weighted;
};
TrueSigmaBounds trueSigmaMoveBound(const gi::VisibilityField& last, const gi::FootprintBox& lastBox,
                                   const gi::VisibilityField& now, const gi::FootprintBox& newBox,
                                   std::span<const double> phi, ConstGridView gradX, ConstGridView gradY,
                                   int subsample);

/// The largest bound over each tile of T x T receivers (row-major tiles)
/// and their neighbours one receiver on: a texel between receivers blends
/// their V (Fig. 7), so a tile's texels may move with a neighbouring tile's
/// receivers (the frames' bound takes the largest of the tiles those
/// receivers belong to).
std::vector<float> tileMaxima(const std::vector<float>& perReceiver, int nxr, int nyr, int T);

}  // namespace terrain::bench
